#include "telemetry/log_format.h"

#include <zlib.h>

#include <cstring>
#include <stdexcept>

namespace hapticd::telemetry {
std::uint32_t crc32_update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

std::vector<std::byte> encode_file_header(const LogHeader& header) {
  const std::size_t config_len = header.config_text.size();
  if (config_len > kMaxConfigBytes) {
    throw std::invalid_argument("tick log: configuration text of " + std::to_string(config_len) +
                                " bytes exceeds the format limit of " +
                                std::to_string(kMaxConfigBytes));
  }
  std::vector<std::byte> out(file_header_size(config_len));
  std::byte* p = out.data();
  std::memcpy(p, kFileMagic.data(), kFileMagic.size());
  store_field<std::uint32_t>(p + 8, kFormatVersion);
  store_field<std::uint32_t>(p + 12, kRecordSize);
  store_field<double>(p + 16, header.sample_period_s);
  store_field<std::int64_t>(p + 24, header.start_unix_ns);
  store_field<std::uint32_t>(p + 32, header.clock_mode);
  store_field<std::uint32_t>(p + 36, static_cast<std::uint32_t>(config_len));
  if (config_len > 0) std::memcpy(p + kFileHeaderFixedSize, header.config_text.data(), config_len);
  const std::size_t crc_at = kFileHeaderFixedSize + config_len;
  store_field<std::uint32_t>(p + crc_at, crc32_update(0, std::span(out).first(crc_at)));
  return out;
}

std::size_t encode_block(std::span<std::byte> out, std::uint64_t first_tick,
                         std::uint64_t dropped_before,
                         std::span<const TickRecord> records) noexcept {
  const std::size_t size = block_size(records.size());
  if (records.size() > kMaxBlockRecords || out.size() < size) return 0;
  std::byte* p = out.data();
  std::memcpy(p, kBlockMagic.data(), kBlockMagic.size());
  store_field<std::uint32_t>(p + 4, static_cast<std::uint32_t>(records.size()));
  store_field<std::uint64_t>(p + 8, first_tick);
  store_field<std::uint64_t>(p + 16, dropped_before);
  if (!records.empty()) std::memcpy(p + kBlockHeaderSize, records.data(), records.size_bytes());
  std::uint32_t crc = crc32_update(0, out.first(kBlockCrcOffset));
  crc = crc32_update(crc, out.subspan(kBlockHeaderSize, records.size_bytes()));
  store_field<std::uint32_t>(p + kBlockCrcOffset, crc);
  return size;
}

namespace {

// A block of text after the 28-byte header (config and counters blocks).
std::vector<std::byte> encode_text_block(const std::array<char, 4>& magic, const char* what,
                                         std::uint64_t first_tick, std::string_view text) {
  if (text.size() > kMaxConfigBytes) {
    throw std::invalid_argument(
        std::string("tick log: ") + what + " text of " + std::to_string(text.size()) +
        " bytes exceeds the format limit of " + std::to_string(kMaxConfigBytes));
  }
  std::vector<std::byte> out(kBlockHeaderSize + text.size());
  std::byte* p = out.data();
  std::memcpy(p, magic.data(), magic.size());
  store_field<std::uint32_t>(p + 4, static_cast<std::uint32_t>(text.size()));
  store_field<std::uint64_t>(p + 8, first_tick);
  store_field<std::uint64_t>(p + 16, 0);
  if (!text.empty()) std::memcpy(p + kBlockHeaderSize, text.data(), text.size());
  std::uint32_t crc = crc32_update(0, std::span(out).first(kBlockCrcOffset));
  crc = crc32_update(crc, std::span(out).subspan(kBlockHeaderSize));
  store_field<std::uint32_t>(p + kBlockCrcOffset, crc);
  return out;
}

}  // namespace

std::vector<std::byte> encode_config_block(std::uint64_t first_tick, std::string_view text) {
  return encode_text_block(kConfigMagic, "configuration", first_tick, text);
}

std::vector<std::byte> encode_counters_block(std::uint64_t first_tick, std::string_view text) {
  return encode_text_block(kCountersMagic, "counters", first_tick, text);
}

BlockHeader decode_block_header(std::span<const std::byte> bytes) noexcept {
  BlockHeader h;
  if (bytes.size() < kBlockHeaderSize) return h;
  const std::byte* p = bytes.data();
  h.record_count = load_field<std::uint32_t>(p + 4);
  h.first_tick = load_field<std::uint64_t>(p + 8);
  h.dropped_before = load_field<std::uint64_t>(p + 16);
  h.crc = load_field<std::uint32_t>(p + kBlockCrcOffset);
  return h;
}

}  // namespace hapticd::telemetry
