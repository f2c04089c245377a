// A tick log in an older format version as the daemon of that version wrote it: the same file
// header with its version and record size, and one block of records cut to that version's size
// (version 1: 72 bytes, 2: 96, 3: 112, 4: 176; what follows in today's record is dropped).
#pragma once

#include <cstring>
#include <span>
#include <vector>

#include "telemetry/log_format.h"

namespace hapticd::testing {

inline std::vector<std::byte> older_log(std::uint32_t version, const telemetry::LogHeader& header,
                                        const std::vector<telemetry::TickRecord>& rs) {
  const std::uint32_t rsize =
      static_cast<std::uint32_t>(telemetry::record_size_of_version(version));
  std::vector<std::byte> b = telemetry::encode_file_header(header);
  const std::size_t crc_at = b.size() - 4;
  const auto put32 = [&](std::size_t at, std::uint32_t v) { std::memcpy(b.data() + at, &v, 4); };
  put32(8, version);
  put32(12, rsize);
  put32(crc_at, telemetry::crc32_update(0, std::span(b).first(crc_at)));
  const std::size_t block = b.size();
  b.resize(block + 28 + rsize * rs.size());
  std::memcpy(b.data() + block, "HBLK", 4);
  const auto n = static_cast<std::uint32_t>(rs.size());
  const std::uint64_t first = rs.empty() ? 0 : rs.front().tick, dropped = 0;
  std::memcpy(b.data() + block + 4, &n, 4);
  std::memcpy(b.data() + block + 8, &first, 8);
  std::memcpy(b.data() + block + 16, &dropped, 8);
  for (std::size_t i = 0; i < rs.size(); ++i) {
    std::memcpy(b.data() + block + 28 + rsize * i, &rs[i], rsize);
  }
  const auto all = std::span<const std::byte>(b);
  const std::uint32_t crc = telemetry::crc32_update(
      telemetry::crc32_update(0, all.subspan(block, 24)), all.subspan(block + 28, rsize * n));
  put32(block + 24, crc);
  return b;
}

}  // namespace hapticd::testing
