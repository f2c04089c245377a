#include "telemetry/log_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <optional>
#include <string_view>

#include "base/errno_text.h"

namespace hapticd::telemetry {
namespace {

// Matches the magic against however many bytes are present, so a cut inside the magic is a
// truncation and not a foreign file.
template <std::size_t N>
bool magic_prefix_matches(std::span<const std::byte> bytes, const std::array<char, N>& magic) {
  const std::size_t n = std::min(bytes.size(), N);
  return n == 0 || std::memcmp(bytes.data(), magic.data(), n) == 0;  // no memcmp on nullptr
}

std::string at_byte(std::size_t offset) { return " at byte " + std::to_string(offset); }

// Parses the file header into out and returns its size in bytes.
std::size_t read_header(std::span<const std::byte> bytes, const std::string& name, LogHeader& out,
                        std::uint32_t& version_out) {
  const auto fail = [&](const std::string& what) { throw LogFormatError(name + ": " + what); };
  if (!magic_prefix_matches(bytes, kFileMagic)) fail("not a hapticd tick log (bad magic)");
  // The version decides the rest of the layout, so it is checked before anything else.
  if (bytes.size() < 12) fail("truncated header");
  const auto version = load_field<std::uint32_t>(bytes.data() + 8);
  if (record_size_of_version(version) == 0) {
    fail("unsupported log version " + std::to_string(version));
  }
  version_out = version;
  if (bytes.size() < kFileHeaderFixedSize) fail("truncated header");
  const std::byte* p = bytes.data();
  const auto config_len = load_field<std::uint32_t>(p + 36);
  if (config_len > kMaxConfigBytes) {
    fail("corrupt header (configuration length " + std::to_string(config_len) + ")");
  }
  const std::size_t crc_at = kFileHeaderFixedSize + config_len;
  if (bytes.size() < crc_at + kCrcSize) fail("truncated header");
  if (crc32_update(0, bytes.first(crc_at)) != load_field<std::uint32_t>(p + crc_at)) {
    fail("header CRC mismatch");
  }
  const auto record_size = load_field<std::uint32_t>(p + 12);
  if (record_size != record_size_of_version(version)) {
    fail("unsupported record size " + std::to_string(record_size));
  }
  out.sample_period_s = load_field<double>(p + 16);
  out.start_unix_ns = load_field<std::int64_t>(p + 24);
  out.clock_mode = load_field<std::uint32_t>(p + 32);
  out.config_text.assign(reinterpret_cast<const char*>(p + kFileHeaderFixedSize), config_len);
  return crc_at + kCrcSize;
}

// The counters block's text: lines "SOURCE NAME KIND VALUE\n", fields separated by one space,
// KIND "count" or "anomaly", VALUE a decimal u64; nullopt when it is anything else.
std::optional<std::vector<base::CounterReading>> parse_counters(std::string_view text) {
  std::vector<base::CounterReading> out;
  while (!text.empty()) {
    const std::size_t eol = text.find('\n');
    if (eol == std::string_view::npos) return std::nullopt;
    std::string_view line = text.substr(0, eol);
    text.remove_prefix(eol + 1);
    std::array<std::string_view, 4> f;
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t sp = line.find(' ');
      if (sp == std::string_view::npos) return std::nullopt;
      f[i] = line.substr(0, sp);
      line.remove_prefix(sp + 1);
    }
    f[3] = line;
    base::CounterReading r;
    const auto [end, ec] = std::from_chars(f[3].data(), f[3].data() + f[3].size(), r.value);
    if (f[0].empty() || f[1].empty() || ec != std::errc() || end != f[3].data() + f[3].size() ||
        (f[2] != "count" && f[2] != "anomaly")) {
      return std::nullopt;
    }
    r.source = f[0];
    r.name = f[1];
    r.kind = f[2] == "anomaly" ? base::CounterKind::kAnomaly : base::CounterKind::kCount;
    out.push_back(std::move(r));
  }
  return out;
}

// A text block (config or counters) at the start of `block`: its size when complete and
// intact, else 0.
std::size_t check_text_block(std::span<const std::byte> block, std::size_t offset, const char* what,
                             std::string& why) {
  if (block.size() < kBlockHeaderSize) {
    why = std::string("incomplete ") + what + " block" + at_byte(offset) + " (log cut short)";
    return 0;
  }
  const BlockHeader h = decode_block_header(block);  // record_count holds the text length
  if (h.record_count > kMaxConfigBytes) {
    why = std::string("corrupt ") + what + " block" + at_byte(offset);
    return 0;
  }
  const std::size_t size = kBlockHeaderSize + h.record_count;
  if (block.size() < size) {
    why = std::string("incomplete ") + what + " block" + at_byte(offset) + " (log cut short)";
    return 0;
  }
  const auto text = block.subspan(kBlockHeaderSize, h.record_count);
  if (crc32_update(crc32_update(0, block.first(kBlockCrcOffset)), text) != h.crc) {
    why = std::string("CRC mismatch in ") + what + " block" + at_byte(offset);
    return 0;
  }
  return size;
}

bool has_magic(std::span<const std::byte> block, const std::array<char, 4>& magic) {
  return block.size() >= magic.size() && std::memcmp(block.data(), magic.data(), magic.size()) == 0;
}

std::string_view text_of(std::span<const std::byte> block) {
  return {reinterpret_cast<const char*>(block.data()) + kBlockHeaderSize,
          decode_block_header(block).record_count};
}

// One block (records or configuration) at the start of `block`: its size when it is complete
// and intact, else 0 with the reason (offset is for the message).
std::size_t check_block(std::span<const std::byte> block, std::size_t offset, std::size_t rsize,
                        std::string& why) {
  if (has_magic(block, kConfigMagic)) return check_text_block(block, offset, "config", why);
  if (has_magic(block, kCountersMagic)) {
    const std::size_t size = check_text_block(block, offset, "counters", why);
    if (size != 0 && !parse_counters(text_of(block))) {
      why = "malformed counters block" + at_byte(offset);
      return 0;
    }
    return size;
  }
  if (!magic_prefix_matches(block, kBlockMagic)) {
    why = "bad block magic" + at_byte(offset);
    return 0;
  }
  if (block.size() < kBlockHeaderSize) {
    why = "incomplete block" + at_byte(offset) + " (log cut short)";
    return 0;
  }
  const BlockHeader h = decode_block_header(block);
  if (h.record_count > kMaxBlockRecords) {
    why = "corrupt block header" + at_byte(offset) + " (record count " +
          std::to_string(h.record_count) + ")";
    return 0;
  }
  const std::size_t size = block_size(h.record_count, rsize);
  if (block.size() < size) {
    why = "incomplete block" + at_byte(offset) + " (log cut short)";
    return 0;
  }
  const auto payload = block.subspan(kBlockHeaderSize, size - kBlockHeaderSize);
  if (crc32_update(crc32_update(0, block.first(kBlockCrcOffset)), payload) != h.crc) {
    why = "CRC mismatch in block" + at_byte(offset);
    return 0;
  }
  return size;
}

// The offset of the next intact block after a bad one at `from`, or bytes.size() if none:
// one flipped bit must not cost every later block of the log.
std::size_t resynchronise(std::span<const std::byte> bytes, std::size_t from, std::size_t rsize) {
  std::string ignored;
  for (std::size_t at = from + 1; at + kBlockHeaderSize <= bytes.size(); ++at) {
    const auto here = bytes.subspan(at);
    const bool magic = has_magic(here, kBlockMagic) || has_magic(here, kConfigMagic) ||
                       has_magic(here, kCountersMagic);
    if (magic && check_block(bytes.subspan(at), at, rsize, ignored) != 0) {
      return at;
    }
  }
  return bytes.size();
}

void accept_block(std::span<const std::byte> block, std::size_t rsize, LogContents& contents) {
  const BlockHeader h = decode_block_header(block);
  if (has_magic(block, kConfigMagic)) {
    contents.reloads.push_back({h.first_tick, std::string(text_of(block))});
    return;
  }
  if (has_magic(block, kCountersMagic)) {
    contents.counters = *parse_counters(text_of(block));  // checked by check_block
    return;
  }
  // A loss marker has no records: nothing is copied (no memcpy into a null vector).
  const std::byte* p = block.data() + kBlockHeaderSize;
  for (std::uint32_t i = 0; i < h.record_count; ++i, p += rsize) {
    TickRecord r{};  // versions 1 and 2: the fields after their records' bytes stay zero
    std::memcpy(&r, p, rsize);
    contents.records.push_back(r);
  }
  contents.dropped_records += h.dropped_before;
  ++contents.complete_blocks;
}

}  // namespace

LogContents read_log_bytes(std::span<const std::byte> bytes, const std::string& name) {
  LogContents contents;
  std::size_t offset = read_header(bytes, name, contents.header, contents.version);
  const std::size_t rsize = record_size_of_version(contents.version);
  contents.records.reserve((bytes.size() - offset) / rsize);
  while (offset < bytes.size()) {
    std::string why;
    if (const std::size_t size = check_block(bytes.subspan(offset), offset, rsize, why);
        size != 0) {
      accept_block(bytes.subspan(offset), rsize, contents);
      offset += size;
      continue;
    }
    const std::size_t next = resynchronise(bytes, offset, rsize);
    if (next == bytes.size()) {
      contents.trailing_reason = why;
      break;
    }
    contents.skipped.push_back({offset, next - offset, why});
    offset = next;
  }
  contents.trailing_bytes_ignored = bytes.size() - offset;
  return contents;
}

LogContents read_log(const std::string& path) {
  const auto fail = [&](int err) {
    throw LogFormatError(path + ": cannot read: " + base::errno_text(err));
  };
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(errno);
  std::vector<std::byte> bytes;
  int err = 0;
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    err = errno;
  } else {
    // A snapshot of the current size: a log still growing is read up to here.
    bytes.resize(static_cast<std::size_t>(std::max<off_t>(st.st_size, 0)));
    std::size_t got = 0;
    while (got < bytes.size()) {
      const ssize_t r = ::read(fd, bytes.data() + got, bytes.size() - got);
      if (r < 0 && errno == EINTR) continue;
      if (r < 0) {
        err = errno;
        break;
      }
      if (r == 0) break;  // the file shrank since fstat
      got += static_cast<std::size_t>(r);
    }
    bytes.resize(got);
  }
  ::close(fd);
  if (err != 0) fail(err);
  // A directory has no bytes to read on some filesystems instead of failing with EISDIR.
  if (S_ISDIR(st.st_mode)) fail(EISDIR);
  return read_log_bytes(bytes, path);
}

}  // namespace hapticd::telemetry
