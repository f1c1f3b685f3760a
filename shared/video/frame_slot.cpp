#include "shared/video/frame_slot.hpp"

#include <fcntl.h>
#include <linux/futex.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <thread>

#include "shared/video/video_error.hpp"

namespace inspect::video {

namespace {

constexpr std::size_t kHeaderBytes = 4096;
constexpr std::size_t kBufferHeaderBytes = 64;
constexpr uint32_t kBuffers = 3;
constexpr uint32_t kFormatBgr24 = 1;
constexpr uint32_t kStateWriting = 1;
constexpr uint32_t kStateClosed = 2;
constexpr int kMaxSide = 8192;

// Byte offsets of the header's fields (frame_slot.hpp).
enum : std::size_t {
  kOffMagic = 0,
  kOffVersion = 8,
  kOffHeaderBytes = 12,
  kOffWidth = 16,
  kOffHeight = 20,
  kOffStride = 24,
  kOffFormat = 28,
  kOffBuffers = 32,
  kOffPid = 36,
  kOffFpsMilli = 40,
  kOffState = 44,
  kOffBufferStride = 48,
  kOffFrameBytes = 56,
  kOffLatest = 64,
  kOffFutex = 72,
};
// Offsets inside a buffer's header.
enum : std::size_t { kBufLock = 0, kBufSeq = 8, kBufCapture = 16, kBufIndex = 24 };

template <class T>
T get(const uint8_t* base, std::size_t off) {
  T v;
  std::memcpy(&v, base + off, sizeof v);
  return v;
}
template <class T>
void put(uint8_t* base, std::size_t off, T v) {
  std::memcpy(base + off, &v, sizeof v);
}
// The shared words are naturally aligned (the mapping is page-aligned).
template <class T>
T loadAcquire(const uint8_t* base, std::size_t off) {
  return __atomic_load_n(reinterpret_cast<const T*>(base + off), __ATOMIC_ACQUIRE);
}
template <class T>
void storeRelease(uint8_t* base, std::size_t off, T v) {
  __atomic_store_n(reinterpret_cast<T*>(base + off), v, __ATOMIC_RELEASE);
}

std::size_t bufferStride(std::size_t frame_bytes) {
  const std::size_t b = kBufferHeaderBytes + frame_bytes;
  return (b + 4095) / 4096 * 4096;
}

long futex(const void* addr, int op, uint32_t val, const timespec* timeout) {
  return syscall(SYS_futex, addr, op, val, timeout, nullptr, 0);
}

std::string errnoText() { return std::strerror(errno); }

// True when `path` holds a frame slot (the magic at its start).
bool isFrameSlot(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  char magic[8] = {};
  const bool ok = ::read(fd, magic, sizeof magic) == static_cast<ssize_t>(sizeof magic) &&
                  std::memcmp(magic, kFrameSlotMagic, sizeof magic) == 0;
  ::close(fd);
  return ok;
}

}  // namespace

// ---- writer -----------------------------------------------------------------

FrameSlotWriter::FrameSlotWriter(std::string path, int width, int height, double fps)
    : path_(std::move(path)), width_(width), height_(height) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw VideoError(path_ + ": picture size " + std::to_string(width) + "x" + std::to_string(height) +
                     " out of range [1, " + std::to_string(kMaxSide) + "]");
  if (!(fps > 0 && fps <= 1000)) throw VideoError(path_ + ": frame rate out of range (0, 1000]");
  struct stat st{};
  if (::lstat(path_.c_str(), &st) == 0 && (!S_ISREG(st.st_mode) || (st.st_size > 0 && !isFrameSlot(path_))))
    throw VideoError(path_ + ": exists and is not a frame slot (left alone)");

  const std::size_t stride = static_cast<std::size_t>(width) * 3;
  const std::size_t frame_bytes = stride * static_cast<std::size_t>(height);
  const std::size_t buf_stride = bufferStride(frame_bytes);
  map_bytes_ = kHeaderBytes + kBuffers * buf_stride;

  const std::string tmp = path_ + ".tmp-" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) throw VideoError(path_ + ": cannot create (" + errnoText() + ")");
  auto fail = [&](const std::string& what) {
    const std::string why = errnoText();
    ::close(fd);
    ::unlink(tmp.c_str());
    throw VideoError(path_ + ": " + what + " (" + why + ")");
  };
  if (::ftruncate(fd, static_cast<off_t>(map_bytes_)) != 0) fail("cannot size the file");
  void* m = ::mmap(nullptr, map_bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (m == MAP_FAILED) fail("cannot map the file");
  map_ = static_cast<uint8_t*>(m);
  if (::fstat(fd, &st) != 0) {
    ::munmap(map_, map_bytes_);
    fail("cannot stat the file");
  }
  dev_ = st.st_dev;
  ino_ = st.st_ino;
  ::close(fd);

  std::memcpy(map_ + kOffMagic, kFrameSlotMagic, sizeof kFrameSlotMagic);
  put<uint32_t>(map_, kOffVersion, kFrameSlotVersion);
  put<uint32_t>(map_, kOffHeaderBytes, static_cast<uint32_t>(kHeaderBytes));
  put<uint32_t>(map_, kOffWidth, static_cast<uint32_t>(width));
  put<uint32_t>(map_, kOffHeight, static_cast<uint32_t>(height));
  put<uint32_t>(map_, kOffStride, static_cast<uint32_t>(stride));
  put<uint32_t>(map_, kOffFormat, kFormatBgr24);
  put<uint32_t>(map_, kOffBuffers, kBuffers);
  put<uint32_t>(map_, kOffPid, static_cast<uint32_t>(::getpid()));
  put<uint32_t>(map_, kOffFpsMilli, static_cast<uint32_t>(std::lround(fps * 1000.0)));
  put<uint32_t>(map_, kOffState, kStateWriting);
  put<uint64_t>(map_, kOffBufferStride, buf_stride);
  put<uint64_t>(map_, kOffFrameBytes, frame_bytes);
  // Everything above is in place before the file gets its name.
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (::rename(tmp.c_str(), path_.c_str()) != 0) {
    const std::string why = errnoText();
    ::munmap(map_, map_bytes_);
    map_ = nullptr;
    ::unlink(tmp.c_str());
    throw VideoError(path_ + ": cannot put the slot in place (" + why + ")");
  }
}

FrameSlotWriter::~FrameSlotWriter() {
  if (!map_) return;
  storeRelease<uint32_t>(map_, kOffState, kStateClosed);
  __atomic_fetch_add(reinterpret_cast<uint32_t*>(map_ + kOffFutex), 1u, __ATOMIC_RELEASE);
  futex(map_ + kOffFutex, FUTEX_WAKE, INT_MAX, nullptr);
  ::munmap(map_, map_bytes_);
  struct stat st{};
  if (::lstat(path_.c_str(), &st) == 0 && st.st_dev == dev_ && st.st_ino == ino_) ::unlink(path_.c_str());
}

void FrameSlotWriter::write(const uint8_t* bgr, std::size_t step, uint64_t capture_us, uint32_t frame_index) {
  const uint64_t n = ++seq_;
  const std::size_t buf_stride = get<uint64_t>(map_, kOffBufferStride);
  uint8_t* buf = map_ + kHeaderBytes + (n % kBuffers) * buf_stride;
  // Sequence lock: odd while the buffer changes (relaxed store, then a release
  // fence so that no write below is seen before it).
  __atomic_store_n(reinterpret_cast<uint64_t*>(buf + kBufLock), 2 * n - 1, __ATOMIC_RELAXED);
  std::atomic_thread_fence(std::memory_order_release);
  put<uint64_t>(buf, kBufSeq, n);
  put<uint64_t>(buf, kBufCapture, capture_us);
  put<uint32_t>(buf, kBufIndex, frame_index);
  const std::size_t row = static_cast<std::size_t>(width_) * 3;
  uint8_t* px = buf + kBufferHeaderBytes;
  if (step == row) {
    std::memcpy(px, bgr, row * static_cast<std::size_t>(height_));
  } else {
    for (int y = 0; y < height_; ++y) std::memcpy(px + y * row, bgr + y * step, row);
  }
  storeRelease<uint64_t>(buf, kBufLock, 2 * n);
  storeRelease<uint64_t>(map_, kOffLatest, n);
  __atomic_fetch_add(reinterpret_cast<uint32_t*>(map_ + kOffFutex), 1u, __ATOMIC_RELEASE);
  futex(map_ + kOffFutex, FUTEX_WAKE, INT_MAX, nullptr);
}

// ---- reader -----------------------------------------------------------------

FrameSlotReader::FrameSlotReader(std::string path) : path_(std::move(path)) {
  const int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) throw VideoError(path_ + ": not found");
    throw VideoError(path_ + ": cannot open (" + errnoText() + ")");
  }
  struct stat st{};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw VideoError(path_ + ": not a frame slot (not a regular file)");
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size < kHeaderBytes) {
    ::close(fd);
    throw VideoError(path_ + ": not a frame slot (" + std::to_string(size) + " bytes, shorter than its header)");
  }
  void* m = ::mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0);
  const std::string why = errnoText();
  ::close(fd);
  if (m == MAP_FAILED) throw VideoError(path_ + ": cannot map (" + why + ")");
  map_ = static_cast<const uint8_t*>(m);
  map_bytes_ = size;
  auto bad = [&](const std::string& what) {
    ::munmap(const_cast<uint8_t*>(map_), map_bytes_);
    map_ = nullptr;
    throw VideoError(path_ + ": " + what);
  };
  if (std::memcmp(map_ + kOffMagic, kFrameSlotMagic, sizeof kFrameSlotMagic) != 0)
    bad("not a frame slot (no INSPFRM header)");
  const auto version = get<uint32_t>(map_, kOffVersion);
  if (version != kFrameSlotVersion)
    bad("frame slot version " + std::to_string(version) + ", this program reads version " +
        std::to_string(kFrameSlotVersion));
  const auto w = get<uint32_t>(map_, kOffWidth), h = get<uint32_t>(map_, kOffHeight);
  const auto stride = get<uint32_t>(map_, kOffStride);
  const auto buffers = get<uint32_t>(map_, kOffBuffers);
  const auto buf_stride = get<uint64_t>(map_, kOffBufferStride);
  const auto frame_bytes = get<uint64_t>(map_, kOffFrameBytes);
  if (get<uint32_t>(map_, kOffHeaderBytes) != kHeaderBytes || w < 1 || h < 1 || w > kMaxSide || h > kMaxSide ||
      stride != 3 * w || get<uint32_t>(map_, kOffFormat) != kFormatBgr24 || buffers != kBuffers ||
      frame_bytes != static_cast<uint64_t>(stride) * h || buf_stride != bufferStride(frame_bytes))
    bad("bad frame slot header (" + std::to_string(w) + "x" + std::to_string(h) + ", " + std::to_string(buffers) +
        " buffers)");
  const std::size_t need = kHeaderBytes + buffers * buf_stride;
  if (size < need)
    bad("truncated frame slot (" + std::to_string(size) + " bytes, its header needs " + std::to_string(need) + ")");
  width_ = static_cast<int>(w);
  height_ = static_cast<int>(h);
  fps_ = get<uint32_t>(map_, kOffFpsMilli) / 1000.0;
  writer_pid_ = static_cast<pid_t>(get<uint32_t>(map_, kOffPid));
}

FrameSlotReader::~FrameSlotReader() {
  if (map_) ::munmap(const_cast<uint8_t*>(map_), map_bytes_);
}

uint64_t FrameSlotReader::latestSeq() const { return loadAcquire<uint64_t>(map_, kOffLatest); }

bool FrameSlotReader::closed() const { return loadAcquire<uint32_t>(map_, kOffState) == kStateClosed; }

bool FrameSlotReader::writerAlive() const {
  if (writer_pid_ <= 0) return false;
  return ::kill(writer_pid_, 0) == 0 || errno == EPERM;
}

std::optional<SlotFrame> FrameSlotReader::readNewer(uint64_t after, uint8_t* dst, std::size_t step,
                                                    std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  const std::size_t buf_stride = get<uint64_t>(map_, kOffBufferStride);
  const std::size_t row = static_cast<std::size_t>(width_) * 3;
  for (;;) {
    // The futex word before the frame number: a frame published after this
    // load changes the word, so the wait below cannot miss it.
    const uint32_t word = loadAcquire<uint32_t>(map_, kOffFutex);
    const uint64_t n = latestSeq();
    if (n > after) {
      const uint8_t* buf = map_ + kHeaderBytes + (n % kBuffers) * buf_stride;
      const uint64_t v1 = loadAcquire<uint64_t>(buf, kBufLock);
      if ((v1 & 1) == 0 && v1 != 0) {
        SlotFrame f{get<uint64_t>(buf, kBufSeq), get<uint64_t>(buf, kBufCapture), get<uint32_t>(buf, kBufIndex)};
        const uint8_t* px = buf + kBufferHeaderBytes;
        if (step == row) {
          std::memcpy(dst, px, row * static_cast<std::size_t>(height_));
        } else {
          for (int y = 0; y < height_; ++y) std::memcpy(dst + y * step, px + y * row, row);
        }
        // The copy above is done before the lock is read again.
        std::atomic_thread_fence(std::memory_order_acquire);
        const uint64_t v2 = __atomic_load_n(reinterpret_cast<const uint64_t*>(buf + kBufLock), __ATOMIC_RELAXED);
        if (v1 == v2 && f.seq == v1 / 2) return f;
      }
      continue;  // overtaken by the writer: take the newest again
    }
    if (closed()) return std::nullopt;
    const auto now = Clock::now();
    if (now >= deadline) return std::nullopt;
    // Sleep until the next frame (or close), at most 50 ms at a time.
    const auto left = std::min<Clock::duration>(deadline - now, std::chrono::milliseconds(50));
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
    const timespec ts{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
    if (futex(map_ + kOffFutex, FUTEX_WAIT, word, &ts) != 0 && errno != EAGAIN && errno != ETIMEDOUT &&
        errno != EINTR)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));  // no futex here: poll
  }
}

}  // namespace inspect::video
