#include "support/log_oracle.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "support/check.h"
#include "telemetry/log_format.h"
#include "telemetry/log_reader.h"

namespace hapticd::fuzz {
namespace {

using namespace hapticd::telemetry;

constexpr std::size_t kVersionOffset = 8;
constexpr std::size_t kRecordSizeOffset = 12;
constexpr std::size_t kConfigLenOffset = 36;
constexpr std::size_t kRecordCountOffset = 4;

std::uint32_t load_u32(std::span<const std::uint8_t> bytes, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, bytes.data() + at, sizeof v);
  return v;
}

void store_u32(std::span<std::uint8_t> bytes, std::size_t at, std::uint32_t v) {
  std::memcpy(bytes.data() + at, &v, sizeof v);
}

std::uint32_t crc_of(std::span<const std::uint8_t> bytes) {
  return crc32_update(0, std::as_bytes(bytes));
}

// Whether record r is the rsize bytes at `at`, zero-extended (version 1 and 2 records are shorter).
bool record_is(const TickRecord& r, const std::byte* at, std::size_t rsize) {
  const auto* bytes = reinterpret_cast<const std::byte*>(&r);
  for (std::size_t i = rsize; i < sizeof r; ++i) {
    if (bytes[i] != std::byte{0}) return false;
  }
  return std::memcmp(bytes, at, rsize) == 0;
}

// Checks the accepted block at `offset`, of records of rsize bytes: present, intact (its CRC
// recomputed here), and returned as exactly its records from c.records[records...]. Returns
// its size.
std::size_t check_block_at(std::span<const std::uint8_t> input, std::size_t offset,
                           std::size_t rsize, const LogContents& c, std::size_t& records,
                           std::uint64_t& dropped) {
  const std::string at = std::to_string(offset);
  require(offset <= input.size() && input.size() - offset >= kBlockHeaderSize,
          "accepted block past the end of the input", at);
  const auto block = std::as_bytes(input.subspan(offset));
  const BlockHeader h = decode_block_header(block);
  require(std::memcmp(block.data(), kBlockMagic.data(), kBlockMagic.size()) == 0 &&
              h.record_count <= kMaxBlockRecords &&
              block.size() >= block_size(h.record_count, rsize),
          "accepted block without its magic, or with more records than it holds", at);
  const auto payload = block.subspan(kBlockHeaderSize, std::size_t{h.record_count} * rsize);
  require(crc32_update(crc32_update(0, block.first(kBlockCrcOffset)), payload) == h.crc,
          "accepted block whose CRC does not match", at);
  require(records + h.record_count <= c.records.size(), "fewer records returned than accepted", at);
  for (std::size_t i = 0; i < h.record_count; ++i) {
    require(record_is(c.records[records + i], payload.data() + i * rsize, rsize),
            "a returned record differs from its bytes in the block", at);
  }
  records += h.record_count;
  dropped += h.dropped_before;
  return block_size(h.record_count, rsize);
}

// Whether an accepted config block (a live reload's configuration) is at `offset`: its magic,
// a length within the input and the bound, and a CRC that holds. (A record block cannot pass
// for one: its magic differs.)
bool config_block_at(std::span<const std::uint8_t> input, std::size_t offset) {
  if (offset > input.size() || input.size() - offset < kBlockHeaderSize) return false;
  const auto block = std::as_bytes(input.subspan(offset));
  if (std::memcmp(block.data(), kConfigMagic.data(), kConfigMagic.size()) != 0) return false;
  const BlockHeader h = decode_block_header(block);
  if (h.record_count > kMaxConfigBytes || block.size() - kBlockHeaderSize < h.record_count) {
    return false;
  }
  const auto text = block.subspan(kBlockHeaderSize, h.record_count);
  return crc32_update(crc32_update(0, block.first(kBlockCrcOffset)), text) == h.crc;
}

// Checks the config block at `offset` is returned as c.reloads[reload], with its first tick
// and text. Returns its size.
std::size_t check_config_at(std::span<const std::uint8_t> input, std::size_t offset,
                            const LogContents& c, std::size_t reload) {
  const std::string at = std::to_string(offset);
  require(reload < c.reloads.size(), "an intact config block not returned", at);
  const auto block = std::as_bytes(input.subspan(offset));
  const BlockHeader h = decode_block_header(block);
  const ConfigChange& r = c.reloads[reload];
  require(
      r.first_tick == h.first_tick && r.config_text.size() == h.record_count &&
          std::memcmp(r.config_text.data(), block.data() + kBlockHeaderSize, h.record_count) == 0,
      "a returned configuration differs from its config block", at);
  return kBlockHeaderSize + h.record_count;
}

// The oracle's own reading of a counters block's text (log_format.h), char by char: lines
// of four non-empty fields split by single spaces, the third "count" or "anomaly", the fourth
// decimal digits that fit in 64 bits. Empty when the text is not that (`ok` false).
struct OracleCounter {
  std::string source, name, kind;
  std::uint64_t value = 0;
};
std::vector<OracleCounter> oracle_counters(std::string_view text, bool& ok) {
  std::vector<OracleCounter> out;
  std::vector<std::string> fields(1);
  ok = false;
  for (const char ch : text) {
    if (ch == ' ') {
      if (fields.size() == 4) return {};
      fields.emplace_back();
    } else if (ch == '\n') {
      if (fields.size() != 4) return {};
      OracleCounter c{fields[0], fields[1], fields[2], 0};
      if (c.source.empty() || c.name.empty() || (c.kind != "count" && c.kind != "anomaly") ||
          fields[3].empty() || fields[3].size() > 20) {
        return {};
      }
      for (const char d : fields[3]) {
        if (d < '0' || d > '9') return {};
        const std::uint64_t digit = static_cast<std::uint64_t>(d - '0');
        if (c.value > (UINT64_MAX - digit) / 10) return {};
        c.value = c.value * 10 + digit;
      }
      out.push_back(c);
      fields.assign(1, std::string());
    } else {
      fields.back() += ch;
    }
  }
  ok = fields.size() == 1 && fields[0].empty();  // the text ends with a whole line
  return ok ? out : std::vector<OracleCounter>{};
}

// Whether an intact, well-formed counters block is at `offset` (the reader must accept it);
// its counters go to `counters` (the last such block is what the reader returns).
bool counters_block_at(std::span<const std::uint8_t> input, std::size_t offset,
                       std::vector<OracleCounter>& counters) {
  if (offset > input.size() || input.size() - offset < kBlockHeaderSize) return false;
  const auto block = std::as_bytes(input.subspan(offset));
  if (std::memcmp(block.data(), kCountersMagic.data(), kCountersMagic.size()) != 0) return false;
  const BlockHeader h = decode_block_header(block);
  if (h.record_count > kMaxConfigBytes || block.size() - kBlockHeaderSize < h.record_count) {
    return false;
  }
  const auto text = block.subspan(kBlockHeaderSize, h.record_count);
  if (crc32_update(crc32_update(0, block.first(kBlockCrcOffset)), text) != h.crc) return false;
  bool ok = false;
  std::vector<OracleCounter> parsed =
      oracle_counters({reinterpret_cast<const char*>(text.data()), text.size()}, ok);
  if (ok) counters = std::move(parsed);
  return ok;
}

void check_counters(const std::vector<OracleCounter>& want, const LogContents& c) {
  require(want.size() == c.counters.size(), "counters returned differ from the last counters block",
          std::to_string(c.counters.size()));
  for (std::size_t i = 0; i < want.size(); ++i) {
    const base::CounterReading& r = c.counters[i];
    const std::string kind(base::to_string(r.kind));
    require(r.source == want[i].source && r.name == want[i].name && kind == want[i].kind &&
                r.value == want[i].value,
            "a returned counter differs from its line in the counters block", std::to_string(i));
  }
}

// Walks the input in file order as the reader reports it: accepted record and config blocks,
// with the skipped stretches between them, each skipped stretch followed by a block. Returns
// where it ends.
std::size_t check_file_order(std::span<const std::uint8_t> input, const LogContents& c,
                             std::size_t offset, std::size_t rsize) {
  std::size_t records = 0;
  std::size_t blocks = 0;
  std::size_t next_skip = 0;
  std::size_t reloads = 0;
  std::uint64_t dropped = 0;
  bool after_skip = false;
  std::vector<OracleCounter> counters;
  for (;;) {
    // A counters block may follow the last record block (that is where the writer puts it).
    if (counters_block_at(input, offset, counters)) {
      offset +=
          kBlockHeaderSize + decode_block_header(std::as_bytes(input.subspan(offset))).record_count;
      after_skip = false;
      continue;
    }
    if (!(blocks < c.complete_blocks || next_skip < c.skipped.size() ||
          reloads < c.reloads.size())) {
      break;
    }
    if (next_skip < c.skipped.size() && c.skipped[next_skip].offset == offset) {
      const SkippedRegion& s = c.skipped[next_skip++];
      require(!after_skip && s.bytes > 0 && !s.reason.empty() && s.bytes <= input.size() - offset,
              "skipped stretch that is empty, unexplained, past the end or after another",
              std::to_string(offset));
      offset += s.bytes;
      after_skip = true;
      continue;
    }
    if (config_block_at(input, offset)) {
      offset += check_config_at(input, offset, c, reloads++);
      after_skip = false;
      continue;
    }
    require(blocks < c.complete_blocks, "skipped stretch away from the end of the previous block",
            std::to_string(offset));
    offset += check_block_at(input, offset, rsize, c, records, dropped);
    ++blocks;
    after_skip = false;
  }
  require(!after_skip, "a skipped stretch must be followed by an accepted block");
  check_counters(counters, c);
  require(reloads == c.reloads.size(), "configurations returned outside config blocks");
  require(records == c.records.size(), "records returned outside accepted blocks");
  require(dropped == c.dropped_records, "dropped_records is not the sum of dropped_before");
  return offset;
}

}  // namespace

void check_log_read(std::span<const std::uint8_t> input) {
  const std::string name = "fuzz.hlog";
  std::vector<std::byte> bytes(input.size());
  if (!input.empty()) std::memcpy(bytes.data(), input.data(), input.size());
  LogContents c;
  try {
    c = read_log_bytes(bytes, name);
  } catch (const LogFormatError& e) {
    const std::string what = e.what();
    require(what.size() > name.size() + 2 && what.starts_with(name + ": "),
            "LogFormatError that does not name the file", what);
    return;
  }
  require(c.trailing_bytes_ignored <= input.size(), "more bytes ignored than read");
  require(c.trailing_reason.empty() == (c.trailing_bytes_ignored == 0),
          "a reason must be given exactly when bytes are ignored", c.trailing_reason);
  // The header was accepted, so its record_size field is the one the blocks use.
  const std::size_t rsize = load_u32(input, kRecordSizeOffset);
  require(rsize > 0 && rsize <= sizeof(TickRecord), "accepted record size out of range",
          std::to_string(rsize));
  const std::size_t end =
      check_file_order(input, c, file_header_size(c.header.config_text.size()), rsize);
  require(end + c.trailing_bytes_ignored == input.size(),
          "header, blocks, skipped stretches and ignored tail do not add up to the input");
}

std::size_t fix_log_crcs(std::span<std::uint8_t> bytes) {
  if (bytes.size() < file_header_size(0)) return 0;
  const std::size_t config_len = load_u32(bytes, kConfigLenOffset);
  if (config_len > bytes.size() - file_header_size(0)) return 0;
  const std::size_t header_crc_at = kFileHeaderFixedSize + config_len;
  // The version decides the record size, as in the reader; an unknown one: the newest.
  std::size_t rsize = record_size_of_version(load_u32(bytes, kVersionOffset));
  if (rsize == 0) rsize = kRecordSize;
  store_u32(bytes, header_crc_at, crc_of(bytes.first(header_crc_at)));
  std::size_t fixed = 1;
  std::size_t offset = header_crc_at + kCrcSize;
  while (bytes.size() - offset >= kBlockHeaderSize) {
    const std::uint32_t count = load_u32(bytes, offset + kRecordCountOffset);
    if (count > kMaxBlockRecords || bytes.size() - offset < block_size(count, rsize)) break;
    const auto block = bytes.subspan(offset, block_size(count, rsize));
    const std::uint32_t crc = crc32_update(crc_of(block.first(kBlockCrcOffset)),
                                           std::as_bytes(block.subspan(kBlockHeaderSize)));
    store_u32(bytes, offset + kBlockCrcOffset, crc);
    ++fixed;
    offset += block.size();
  }
  return fixed;
}

}  // namespace hapticd::fuzz
