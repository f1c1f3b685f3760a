#pragma once
// Consistent Overhead Byte Stuffing for frames of at most 254 data bytes.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace inspect::serial {

/// Largest unencoded frame the codec handles (one COBS block, one overhead byte).
inline constexpr std::size_t kMaxRawFrame = 254;
/// Largest COBS-encoded frame, without the 0x00 delimiter.
inline constexpr std::size_t kMaxEncodedFrame = kMaxRawFrame + 1;

/// Encodes `in` (<= kMaxRawFrame bytes) into `out` (>= in.size() + 1 bytes).
/// Returns the encoded length (no delimiter is written), or 0 if `in` is too long.
std::size_t cobsEncode(std::span<const uint8_t> in, std::span<uint8_t> out);

/// Decodes one COBS frame (delimiter already removed) into `out`.
/// Returns the decoded length, or nullopt if the frame is not valid COBS.
std::optional<std::size_t> cobsDecode(std::span<const uint8_t> in, std::span<uint8_t> out);

}  // namespace inspect::serial
