#pragma once
// The constants of the MCAP format that the writer and the reader share
// (https://mcap.dev/spec, "Records" and "Magic").
#include <cstdint>
#include <string_view>

namespace inspect::record::mcap {

inline constexpr std::string_view kMagic("\x89MCAP0\r\n", 8);

// Record opcodes (spec "Records").
enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

inline constexpr uint64_t kRecordPrefix = 9;                    // opcode u8 + content length u64
inline constexpr uint64_t kFooterRecord = kRecordPrefix + 20;  // summary_start, summary_offset_start, summary_crc

}  // namespace inspect::record::mcap
