#pragma once
// The video layer's one error type.
#include <stdexcept>

namespace inspect::video {

/// Any failure of the video layer that the caller should report (bad device,
/// codec missing, bad settings). The message names what was wrong.
class VideoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace inspect::video
