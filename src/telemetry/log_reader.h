// Reads a binary tick log (format in log_format.h), including one cut short by a crash or
// a full disk: every complete, CRC-valid block is returned, and the first block that is not
// ends the read with the reason and the number of bytes ignored. Not RT-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "telemetry/log_format.h"
#include "telemetry/tick_record.h"

namespace hapticd::telemetry {

struct LogContents {
  LogHeader header;
  std::vector<TickRecord> records;           // every record of every accepted block, in file order
  std::size_t complete_blocks = 0;           // blocks accepted, loss markers included
  std::uint64_t dropped_records = 0;         // sum of dropped_before: ticks missing from the log
  std::uint64_t trailing_bytes_ignored = 0;  // bytes after the last accepted block
  // "" when the whole file was read, else why reading stopped, e.g.
  // "incomplete block at byte 4242 (log cut short)", "CRC mismatch in block at byte 4242",
  // "bad block magic at byte 4242", "corrupt block header at byte 4242 (record count 9999999)".
  std::string trailing_reason;
};

// The file is not a readable tick log at all. what() starts with the file name, e.g.
// "PATH: not a hapticd tick log (bad magic)", "PATH: truncated header",
// "PATH: header CRC mismatch", "PATH: unsupported log version N", "PATH: cannot read: REASON".
class LogFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads the file as it is at the time of the call (a log still being written is read up to
// its current size). Throws LogFormatError.
LogContents read_log(const std::string& path);

// Parses a log held in memory; name prefixes the error messages. Throws LogFormatError.
LogContents read_log_bytes(std::span<const std::byte> bytes, const std::string& name);

}  // namespace hapticd::telemetry
