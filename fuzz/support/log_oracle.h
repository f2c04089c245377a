// What the log reader fuzz targets assert, and the CRC repair that lets mutated logs reach the
// structure behind the checksums.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace hapticd::fuzz {

// Reads input with telemetry::read_log_bytes as read_log does (from a std::vector, so an empty
// input has no storage, like an empty file). A LogFormatError must name the file; anything
// else thrown escapes. A successful read must account for every input byte in file order
// (header, accepted blocks, the stretches it skipped to resynchronise, the ignored tail),
// accept only blocks whose CRC holds, and return exactly the records of those blocks (a
// version 1 record zero-extended).
void check_log_read(std::span<const std::uint8_t> input);

// Walks bytes as a tick log as far as its lengths allow and rewrites the header CRC and each
// block CRC to match the bytes they cover. Magics, versions and lengths are left as they are,
// so the reader's other checks still see the mutation. Returns how many CRCs it wrote.
std::size_t fix_log_crcs(std::span<std::uint8_t> bytes);

}  // namespace hapticd::fuzz
