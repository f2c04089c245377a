// Reads a binary tick log (format in log_format.h), including one cut short by a crash or
// a full disk, or damaged in the middle: every complete, CRC-valid block is returned; a bad
// block is skipped up to the next intact block header (reported in `skipped`), and when no
// intact block follows, the read ends with the reason and the bytes ignored. Not RT-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/counters.h"
#include "telemetry/log_format.h"
#include "telemetry/tick_record.h"

namespace hapticd::telemetry {

// A stretch of a log that did not parse as intact blocks but was followed by one that did.
struct SkippedRegion {
  std::size_t offset = 0;  // first byte skipped
  std::size_t bytes = 0;
  std::string
      reason;  // why the block at `offset` was refused, e.g. "CRC mismatch in block at byte 4242"
};

// A live reload recorded in the log: the configuration that governs from first_tick on.
struct ConfigChange {
  std::uint64_t first_tick = 0;
  std::string config_text;
};

struct LogContents {
  LogHeader header;
  std::uint32_t version = kFormatVersion;    // of the file; version 1 records read with zeros
  std::vector<TickRecord> records;           // every record of every accepted block, in file order
  std::size_t complete_blocks = 0;           // blocks accepted, loss markers included
  std::uint64_t dropped_records = 0;         // sum of dropped_before: ticks missing from the log
  std::uint64_t trailing_bytes_ignored = 0;  // bytes after the last accepted block
  // Corrupt stretches passed over to reach later intact blocks (the reader resynchronises on
  // the next block header whose CRC holds); the ticks they held are missing from `records`.
  std::vector<SkippedRegion> skipped;
  // Config blocks, in order: live reloads and re-armings after a cleared fault (their marker
  // records say which); header.config_text governs before the first.
  std::vector<ConfigChange> reloads;
  // The run's counters as the log's counters block recorded them when it ended (the last
  // such block read); empty for a log without one (an older one, or cut short by a crash).
  std::vector<base::CounterReading> counters;
  // "" when the whole file was read, else why reading stopped, e.g.
  // "incomplete block at byte 4242 (log cut short)", "CRC mismatch in block at byte 4242",
  // "bad block magic at byte 4242", "corrupt block header at byte 4242 (record count 9999999)".
  std::string trailing_reason;
};

// The file is not a readable tick log at all. what() starts with the file name, e.g.
// "PATH: not a hapticd tick log (bad magic)", "PATH: truncated header",
// "PATH: header CRC mismatch", "PATH: unsupported log version N", "PATH: cannot read: REASON".
// Versions 1 and 2 are read.
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
