// The frame slot (shared/video/frame_slot.hpp) between a writer and a reader
// thread: every picture whole (no tearing) and in order; its errors, which
// name the path; and the `sim:PATH` video source on top of it (resizing, a
// simulator that stops writing or closes, bad paths). Every loop and wait is
// bounded; nothing is judged by time.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/video/frame_slot.hpp"
#include "shared/video/frame_source.hpp"
#include "shared/video/timecode.hpp"
#include "tests/support/process.hpp"

using namespace inspect::video;
using namespace std::chrono_literals;

namespace {

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const VideoError& e) {
    return e.what();
  }
  return "";
}

// Picture n of a test stream: every byte (n * 7 + row) mod 256, so that a
// picture mixing two frames, or rows out of place, is seen.
void fill(cv::Mat& m, uint64_t n) {
  for (int r = 0; r < m.rows; ++r) std::memset(m.ptr(r), static_cast<int>((n * 7 + r) & 0xFF), m.cols * 3);
}
bool whole(const cv::Mat& m, uint64_t n) {
  for (int r = 0; r < m.rows; ++r) {
    const uint8_t v = static_cast<uint8_t>((n * 7 + r) & 0xFF);
    const uint8_t* p = m.ptr(r);
    for (int i = 0; i < m.cols * 3; ++i)
      if (p[i] != v) return false;
  }
  return true;
}

// A writer on its own thread: `count` pictures, `period` apart (0: flat out).
class WriterThread {
 public:
  WriterThread(FrameSlotWriter& w, int count, std::chrono::microseconds period, bool timecode = false)
      : thread_([&w, count, period, timecode, this] {
          cv::Mat pic(w.height(), w.width(), CV_8UC3);
          for (int k = 1; k <= count && !stop_; ++k) {
            fill(pic, static_cast<uint64_t>(k));
            if (timecode) drawTimecode(pic, 1000000ull + 1000ull * k, static_cast<uint32_t>(k + 100));
            w.write(pic.data, pic.step, 1000000ull + 1000ull * k, static_cast<uint32_t>(k + 100));
            if (period.count() > 0) std::this_thread::sleep_for(period);
          }
        }) {}
  ~WriterThread() {
    stop_ = true;
    finish();
  }
  /// Waits until all `count` pictures are written.
  void finish() {
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

TEST(FrameSlot, RoundTripsPicturesBetweenAWriterAndAReaderThreadWithoutTearing) {
  inspect::test::TempDir dir("frame_slot");
  const std::string path = dir / "cam.slot";
  FrameSlotWriter writer(path, 320, 240, 30);
  FrameSlotReader reader(path);
  EXPECT_EQ(reader.width(), 320);
  EXPECT_EQ(reader.height(), 240);
  EXPECT_EQ(reader.writerPid(), ::getpid());
  EXPECT_TRUE(reader.writerAlive());
  EXPECT_EQ(reader.latestSeq(), 0u);
  constexpr int kFrames = 3000;
  int read = 0, torn = 0;
  uint64_t last = 0;
  std::thread consumer([&] {
    cv::Mat pic(240, 320, CV_8UC3);
    // Bounded: at most kFrames reads, each waiting at most 2 s.
    for (int i = 0; i < kFrames && last < kFrames; ++i) {
      const auto f = reader.readNewer(last, pic.data, pic.step, 2000ms);
      if (!f) break;
      if (f->seq <= last || !whole(pic, f->seq) || f->capture_us != 1000000ull + 1000ull * f->seq ||
          f->frame_index != f->seq + 100)
        ++torn;
      last = f->seq;
      ++read;
    }
  });
  WriterThread(writer, kFrames, 0us).finish();  // flat out: the reader is overtaken and must retry
  consumer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(last, static_cast<uint64_t>(kFrames)) << "the newest picture is always there";
  EXPECT_GE(read, 2);
  EXPECT_EQ(writer.framesWritten(), static_cast<uint64_t>(kFrames));
  std::printf("frame slot: %d of %d pictures read whole by a reader racing a flat-out writer\n", read, kFrames);

  // A picture into rows with padding (a cv::Mat region) comes out the same.
  cv::Mat wide(240, 400, CV_8UC3, cv::Scalar::all(0));
  cv::Mat region = wide(cv::Rect(40, 0, 320, 240));
  fill(region, 9);
  writer.write(region.data, region.step, 5, 6);
  cv::Mat back(240, 320, CV_8UC3);
  const auto f = reader.readNewer(last, back.data, back.step, 1000ms);
  ASSERT_TRUE(f);
  EXPECT_TRUE(whole(back, 9));
  EXPECT_EQ(f->frame_index, 6u);
}

TEST(FrameSlot, AWaitIsBoundedAndAClosedSlotIsSeenAtOnce) {
  inspect::test::TempDir dir("frame_slot");
  const std::string path = dir / "cam.slot";
  auto writer = std::make_unique<FrameSlotWriter>(path, 64, 64, 30);
  FrameSlotReader reader(path);
  cv::Mat pic(64, 64, CV_8UC3);
  EXPECT_FALSE(reader.readNewer(0, pic.data, pic.step, 100ms)) << "nothing written yet";
  EXPECT_FALSE(reader.closed());
  writer.reset();
  EXPECT_FALSE(inspect::test::exists(path)) << "the writer removes its file";
  EXPECT_TRUE(reader.closed());
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(reader.readNewer(0, pic.data, pic.step, 5000ms));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 2500ms);
}

TEST(FrameSlot, ErrorsNameThePath) {
  inspect::test::TempDir dir("frame_slot");
  const std::string missing = dir / "missing.slot";
  EXPECT_EQ(errorOf([&] { FrameSlotReader r(missing); }), missing + ": not found");

  const std::string text = dir / "notes.txt";
  inspect::test::writeFile(text, std::string(5000, 'x'));
  EXPECT_EQ(errorOf([&] { FrameSlotReader r(text); }), text + ": not a frame slot (no INSPFRM header)");
  const std::string empty = dir / "empty";
  inspect::test::writeFile(empty, "");
  EXPECT_EQ(errorOf([&] { FrameSlotReader r(empty); }),
            empty + ": not a frame slot (0 bytes, shorter than its header)");
  EXPECT_NE(errorOf([&] { FrameSlotReader r(dir.path()); }).find(dir.path() + ": "), std::string::npos);

  // A slot cut short, and one of another version.
  const std::string good = dir / "good.slot";
  FrameSlotWriter writer(good, 64, 64, 30);
  const std::string cut = dir / "cut.slot";
  std::filesystem::copy_file(good, cut);
  std::filesystem::resize_file(cut, 4096 + 100);
  EXPECT_NE(errorOf([&] { FrameSlotReader r(cut); }).find(cut + ": truncated frame slot (4196 bytes"), std::string::npos);
  const std::string v2 = dir / "v2.slot";
  std::filesystem::copy_file(good, v2);
  {
    const int fd = ::open(v2.c_str(), O_WRONLY);
    const uint32_t seven = 7;
    ASSERT_EQ(::pwrite(fd, &seven, 4, 8), 4);
    ::close(fd);
  }
  EXPECT_EQ(errorOf([&] { FrameSlotReader r(v2); }),
            v2 + ": frame slot version 7, this program reads version 1");

  // The writer leaves anything that is not a frame slot alone; bad settings.
  EXPECT_EQ(errorOf([&] { FrameSlotWriter w(text, 64, 64, 30); }), text + ": exists and is not a frame slot (left alone)");
  EXPECT_EQ(inspect::test::readFile(text), std::string(5000, 'x'));
  EXPECT_NE(errorOf([&] { FrameSlotWriter w(dir / "no/such/dir/x.slot", 64, 64, 30); }).find(": cannot create ("),
            std::string::npos);
  EXPECT_NE(errorOf([&] { FrameSlotWriter w(dir / "big.slot", 9000, 64, 30); }).find("picture size 9000x64 out of range"),
            std::string::npos);
}

TEST(FrameSlot, ANewWriterReplacesAnOldSlotAndTheOldOneLeavesItInPlace) {
  inspect::test::TempDir dir("frame_slot");
  const std::string path = dir / "cam.slot";
  auto first = std::make_unique<FrameSlotWriter>(path, 64, 64, 30);
  FrameSlotReader old_reader(path);
  FrameSlotWriter second(path, 128, 96, 15);
  FrameSlotReader new_reader(path);
  EXPECT_EQ(new_reader.width(), 128);
  EXPECT_EQ(old_reader.width(), 64);
  first.reset();  // the file is the second writer's now: not removed
  EXPECT_TRUE(inspect::test::exists(path));
  EXPECT_TRUE(old_reader.closed());
  EXPECT_FALSE(new_reader.closed());
}

TEST(SimSource, GivesTheSimulatorsPicturesResizedToTheAskedSize) {
  inspect::test::TempDir dir("sim_source");
  const std::string path = dir / "cam.slot";
  FrameSlotWriter writer(path, 640, 480, 100);
  WriterThread w(writer, 2000, 10000us, true);  // 100 fps, for at most 20 s
  SourceSettings s;
  s.uri = "sim:" + path;
  s.width = 320;
  s.height = 240;
  s.fps = 100;
  auto src = openFrameSource(s);
  EXPECT_TRUE(src->paced());
  EXPECT_NE(src->describe().find("sim:" + path + " (mcu_sim pid " + std::to_string(::getpid()) +
                                 ", 640x480 at 100 fps, out 320x240)"),
            std::string::npos)
      << src->describe();
  uint32_t last_index = 0;
  for (int k = 0; k < 5; ++k) {
    cv::Mat bgr;
    ASSERT_TRUE(src->read(bgr, 0, 0)) << src->error();
    ASSERT_EQ(bgr.cols, 320);
    ASSERT_EQ(bgr.rows, 240);
    const auto code = readTimecode(bgr);  // the simulator's own, resized with the picture
    ASSERT_TRUE(code);
    EXPECT_GT(code->frame_index, last_index) << "a newer picture each time";
    last_index = code->frame_index;
  }
  // The same size: the picture as written.
  s.width = 640;
  s.height = 480;
  auto same = openFrameSource(s);
  cv::Mat bgr;
  ASSERT_TRUE(same->read(bgr, 0, 0)) << same->error();
  ASSERT_TRUE(readTimecode(bgr));
}

TEST(SimSource, ReportsASimulatorThatStopsWritingOrCloses) {
  inspect::test::TempDir dir("sim_source");
  const std::string path = dir / "cam.slot";
  auto writer = std::make_unique<FrameSlotWriter>(path, 64, 64, 30);
  SourceSettings s;
  s.uri = "sim:" + path;
  s.width = 64;
  s.height = 64;
  WriterThread(*writer, 1, 0us).finish();
  auto src = openFrameSource(s);
  cv::Mat bgr;
  ASSERT_TRUE(src->read(bgr, 0, 0)) << "the newest picture, at once";
  EXPECT_TRUE(whole(bgr, 1));
  // Nothing new: the wait ends (kSimStallTimeoutMs) with the reason.
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(src->read(bgr, 0, 0));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);
  EXPECT_EQ(src->error(), "sim:" + path + ": no new picture for 1.0 s (mcu_sim pid " + std::to_string(::getpid()) +
                              " is running but not writing)");
  // The writer goes away: the source says so at once.
  auto again = openFrameSource(s);
  writer.reset();
  EXPECT_TRUE(again->read(bgr, 0, 0)) << "the last picture is still there";
  EXPECT_FALSE(again->read(bgr, 0, 0));
  EXPECT_EQ(again->error(), "sim:" + path + ": mcu_sim closed the camera (it stopped)");
  EXPECT_EQ(errorOf([&] { openFrameSource(s); }),
            "sim:" + path + ": not found (is mcu_sim running with --camera " + path + "?)");
}

TEST(SimSource, NamesAWriterThatHasExited) {
  inspect::test::TempDir dir("sim_source");
  const std::string path = dir / "cam.slot";
  FrameSlotWriter writer(path, 64, 64, 30);
  {
    // A slot left behind by a killed simulator: its pid names no process.
    const int fd = ::open(path.c_str(), O_WRONLY);
    const uint32_t gone = 0x7FFFFFF0;
    ASSERT_EQ(::pwrite(fd, &gone, 4, 36), 4);
    ::close(fd);
  }
  SourceSettings s;
  s.uri = "sim:" + path;
  auto src = openFrameSource(s);
  cv::Mat bgr;
  EXPECT_FALSE(src->read(bgr, 0, 0));
  EXPECT_EQ(src->error(), "sim:" + path + ": no new picture for 1.0 s (mcu_sim pid 2147483632 has exited)");
}

TEST(SimSource, BadPathsAreClearErrors) {
  inspect::test::TempDir dir("sim_source");
  SourceSettings s;
  s.uri = "sim:";
  EXPECT_EQ(errorOf([&] { openFrameSource(s); }), "video source 'sim:': no path (sim:PATH, the file of mcu_sim --camera PATH)");
  s.uri = "sim:" + (dir / "nothing");
  EXPECT_EQ(errorOf([&] { openFrameSource(s); }),
            "sim:" + (dir / "nothing") + ": not found (is mcu_sim running with --camera " + (dir / "nothing") + "?)");
  inspect::test::writeFile(dir / "text", std::string(8192, 't'));
  s.uri = "sim:" + (dir / "text");
  EXPECT_EQ(errorOf([&] { openFrameSource(s); }), "sim:" + (dir / "text") + ": not a frame slot (no INSPFRM header)");
  s.uri = "bogus";
  EXPECT_NE(errorOf([&] { openFrameSource(s); }).find("sim:PATH"), std::string::npos) << "listed as a choice";
}
