#pragma once
// What the MCAP tests share: their log-time base and units, and whole-file
// reads and writes of recordings.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>

namespace inspect::test {

inline constexpr uint64_t kMs = 1'000'000;                   // ns
inline constexpr uint64_t kSecond = 1'000 * kMs;             // ns
inline constexpr uint64_t kBase = 1'763'800'000 * kSecond;  // log times: Unix time in ns

/// The whole file (empty when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Replaces the file with `bytes`.
inline void spit(const std::filesystem::path& p, std::string_view bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace inspect::test
