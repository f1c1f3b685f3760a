// VideoSender with `stream` false: the wide head's capture (robot_client
// wide_head), pictures for the picture tap only: no encoder, no socket.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include "shared/video/video_sender.hpp"

using namespace inspect::video;

TEST(VideoCaptureOnly, TapsPicturesAtTheSourceRateWithoutEncodingOrADestination) {
  SenderSettings s;
  s.stream = false;
  s.host = "";  // no destination: not needed, not checked
  s.port = 0;
  s.source.uri = "synthetic";
  s.source.width = 480;
  s.source.height = 360;
  s.source.fps = 20;
  VideoSender sender(s);
  std::mutex mu;
  int pictures = 0, wrong_size = 0;
  uint64_t last_us = 0;
  int out_of_order = 0;
  sender.setPictureTap([&](const cv::Mat& bgr, uint64_t us) {
    std::lock_guard lk(mu);
    ++pictures;
    if (bgr.cols != 480 || bgr.rows != 360 || bgr.type() != CV_8UC3) ++wrong_size;
    if (us <= last_us) ++out_of_order;
    last_us = us;
  });
  sender.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  sender.stop();
  const SenderStats st = sender.stats();
  std::lock_guard lk(mu);
  // 20 fps for 0.6 s: about 12 (the first at once).
  EXPECT_GE(pictures, 8);
  EXPECT_LE(pictures, 14);
  EXPECT_EQ(wrong_size, 0);
  EXPECT_EQ(out_of_order, 0);
  EXPECT_EQ(st.captured, static_cast<uint64_t>(pictures));
  EXPECT_EQ(st.encoded, 0u);
  EXPECT_EQ(st.packets, 0u);
  EXPECT_EQ(st.error, "");
}

TEST(VideoCaptureOnly, BadSourceSettingsAreRefusedByName) {
  SenderSettings s;
  s.stream = false;
  s.source.fps = 500;
  try {
    VideoSender sender(s);
    FAIL() << "fps 500 accepted";
  } catch (const VideoError& e) {
    EXPECT_NE(std::string(e.what()).find("fps"), std::string::npos) << e.what();
  }
  s.source.fps = 15;
  s.source.width = 481;
  try {
    VideoSender sender(s);
    FAIL() << "an odd width accepted";
  } catch (const VideoError& e) {
    EXPECT_NE(std::string(e.what()).find("width"), std::string::npos) << e.what();
  }
}
