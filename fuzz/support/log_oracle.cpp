#include "support/log_oracle.h"

#include <cstring>
#include <string>
#include <vector>

#include "support/check.h"
#include "telemetry/log_format.h"
#include "telemetry/log_reader.h"

namespace hapticd::fuzz {
namespace {

using namespace hapticd::telemetry;

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

// Walks the blocks the reader accepted, from the input itself, and compares.
void check_accepted_blocks(std::span<const std::uint8_t> input, const LogContents& c,
                           std::size_t offset) {
  std::size_t records = 0;
  std::uint64_t dropped = 0;
  for (std::size_t b = 0; b < c.complete_blocks; ++b) {
    const auto block = std::as_bytes(input.subspan(offset));
    require(block.size() >= kBlockHeaderSize &&
                std::memcmp(block.data(), kBlockMagic.data(), kBlockMagic.size()) == 0,
            "accepted block without its magic", std::to_string(offset));
    const BlockHeader h = decode_block_header(block);
    require(h.record_count <= kMaxBlockRecords && records + h.record_count <= c.records.size(),
            "accepted block with more records than returned", std::to_string(offset));
    const std::size_t payload = std::size_t{h.record_count} * kRecordSize;
    require(payload == 0 || std::memcmp(c.records.data() + records, block.data() + kBlockHeaderSize,
                                        payload) == 0,
            "returned records differ from the bytes of their block", std::to_string(offset));
    records += h.record_count;
    dropped += h.dropped_before;
    offset += block_size(h.record_count);
  }
  require(records == c.records.size(), "records returned outside accepted blocks");
  require(dropped == c.dropped_records, "dropped_records is not the sum of dropped_before");
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
  const std::size_t header = file_header_size(c.header.config_text.size());
  require(c.trailing_bytes_ignored <= input.size(), "more bytes ignored than read");
  require(c.records.size() <= c.complete_blocks * std::size_t{kMaxBlockRecords},
          "more records than the accepted blocks can hold");
  require(header + c.complete_blocks * kBlockHeaderSize + c.records.size() * kRecordSize +
                  c.trailing_bytes_ignored ==
              input.size(),
          "header, accepted blocks and ignored tail do not add up to the input");
  require(c.trailing_reason.empty() == (c.trailing_bytes_ignored == 0),
          "a reason must be given exactly when bytes are ignored", c.trailing_reason);
  check_accepted_blocks(input, c, header);
}

std::size_t fix_log_crcs(std::span<std::uint8_t> bytes) {
  if (bytes.size() < file_header_size(0)) return 0;
  const std::size_t config_len = load_u32(bytes, kConfigLenOffset);
  if (config_len > bytes.size() - file_header_size(0)) return 0;
  const std::size_t header_crc_at = kFileHeaderFixedSize + config_len;
  store_u32(bytes, header_crc_at, crc_of(bytes.first(header_crc_at)));
  std::size_t fixed = 1;
  std::size_t offset = header_crc_at + kCrcSize;
  while (bytes.size() - offset >= kBlockHeaderSize) {
    const std::uint32_t count = load_u32(bytes, offset + kRecordCountOffset);
    if (count > kMaxBlockRecords || bytes.size() - offset < block_size(count)) break;
    const auto block = bytes.subspan(offset, block_size(count));
    const std::uint32_t crc = crc32_update(crc_of(block.first(kBlockCrcOffset)),
                                           std::as_bytes(block.subspan(kBlockHeaderSize)));
    store_u32(bytes, offset + kBlockCrcOffset, crc);
    ++fixed;
    offset += block.size();
  }
  return fixed;
}

}  // namespace hapticd::fuzz
