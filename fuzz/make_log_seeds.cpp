// Writes the seed corpus of the log reader targets with the project's own writer, so the
// seeds follow the format wherever it goes, and checks on every seed that fix_log_crcs
// repairs each checksum a mutation breaks: the CRC target explores nothing past the first
// checksum if it does not. Usage: fuzz_make_log_seeds OUT_DIR. Exit 1 on a failed check.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "support/log_oracle.h"
#include "telemetry/log_format.h"
#include "telemetry/log_reader.h"
#include "telemetry/log_writer.h"

namespace {

namespace fs = std::filesystem;
namespace tel = hapticd::telemetry;
using Bytes = std::vector<std::uint8_t>;

int g_failures = 0;

void expect(bool ok, const std::string& what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_make_log_seeds: FAILED: %s\n", what.c_str());
  ++g_failures;
}

std::vector<tel::TickRecord> records(std::size_t n) {
  std::vector<tel::TickRecord> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    tel::TickRecord& r = out[i];
    r.tick = i;
    r.scheduled_ns = static_cast<std::int64_t>(i) * 1000000;
    r.position = 0.001 * static_cast<double>(i) - 0.002;
    r.penetration = r.position;
    r.velocity = 1.0;
    r.force_computed = r.penetration > 0.0 ? 2000.0 * r.penetration : 0.0;
    r.force_commanded = -r.force_computed;
    r.flags = r.penetration > 0.0 ? tel::kFlagContact : 0u;
    r.sample_time_ns = r.scheduled_ns - 20000;
    r.sequence = static_cast<std::uint32_t>(i + 1);
    r.observer_energy_j = 1e-4 * static_cast<double>(i);
    r.passivity_damping = i == 3 ? 4.5 : 0.0;
    if (i == 3) r.flags |= tel::kFlagPassivityDamped;
  }
  return out;
}

Bytes read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& path, const Bytes& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

std::uint32_t le32(const Bytes& bytes, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, bytes.data() + at, sizeof v);
  return v;
}

// Blocks read back from bytes, or -1 when the header itself is refused.
long blocks_read(const Bytes& bytes) {
  try {
    return static_cast<long>(
        tel::read_log_bytes(std::as_bytes(std::span(bytes)), "seed").complete_blocks);
  } catch (const tel::LogFormatError&) {
    return -1;
  }
}

// Breaks the byte at `at` of a valid log, repairs the CRCs, and expects every block back.
void expect_repaired(const std::string& name, const Bytes& valid, std::size_t at, long blocks) {
  Bytes broken = valid;
  broken[at] ^= 0x5a;
  expect(blocks_read(broken) < blocks,
         name + ": corrupting byte " + std::to_string(at) + " must lose a block before the repair");
  hapticd::fuzz::fix_log_crcs(broken);
  expect(blocks_read(broken) == blocks,
         name + ": fix_log_crcs must make byte " + std::to_string(at) + "'s change readable");
}

// On a valid log the repair changes nothing; every CRC it covers and every payload byte
// it protects, once broken, is repaired.
void check_fixer(const std::string& name, const Bytes& valid) {
  const std::size_t rsize = tel::record_size_of_version(le32(valid, 8));
  const long blocks = blocks_read(valid);
  expect(blocks >= 0, name + ": the writer's log must read back");
  Bytes copy = valid;
  const std::size_t fixed = hapticd::fuzz::fix_log_crcs(copy);
  expect(copy == valid && fixed == static_cast<std::size_t>(blocks) + 1,
         name + ": fix_log_crcs must leave a valid log as it is");
  std::size_t offset = tel::file_header_size(le32(valid, 36));
  expect_repaired(name, valid, offset - 1, blocks);  // the header CRC
  expect_repaired(name, valid, 16, blocks);          // the sample period, under the header CRC
  while (offset < valid.size()) {
    const std::size_t n = le32(valid, offset + 4);
    expect_repaired(name, valid, offset + tel::kBlockCrcOffset, blocks);
    expect_repaired(name, valid, offset + 8, blocks);  // first_tick, under the block CRC
    if (n > 0) expect_repaired(name, valid, offset + tel::block_size(n, rsize) - 1, blocks);
    offset += tel::block_size(n, rsize);
  }
}

fs::path write_seed(const fs::path& dir, const std::string& name, const std::string& config,
                    std::uint32_t clock, std::size_t n, std::size_t per_block) {
  tel::LogHeader header;
  header.sample_period_s = 0.001;
  header.clock_mode = clock;
  header.start_unix_ns = clock == tel::kClockModeFreerun ? 0 : 1700000000000000000;
  header.config_text = config;
  const fs::path path = dir / (name + ".hlog");
  fs::remove(path);  // regenerated on every run; the writer refuses to replace a file
  tel::write_log_file(path, header, records(n), per_block);
  check_fixer(name, read_bytes(path));
  return path;
}

// The same log in an older format version, which the reader still accepts: shorter records
// (the first bytes of the current version's), CRCs recomputed.
Bytes to_version(const Bytes& current, std::uint32_t version) {
  const std::size_t header = tel::file_header_size(le32(current, 36));
  Bytes old(current.begin(), current.begin() + static_cast<std::ptrdiff_t>(header));
  const auto record_size = static_cast<std::uint32_t>(tel::record_size_of_version(version));
  std::memcpy(old.data() + 8, &version, sizeof version);
  std::memcpy(old.data() + 12, &record_size, sizeof record_size);
  for (std::size_t at = header; at < current.size();) {
    const std::size_t n = le32(current, at + 4);
    old.insert(old.end(), current.begin() + static_cast<std::ptrdiff_t>(at),
               current.begin() + static_cast<std::ptrdiff_t>(at + tel::kBlockHeaderSize));
    for (std::size_t i = 0; i < n; ++i) {
      const auto record = current.begin() + static_cast<std::ptrdiff_t>(at + tel::kBlockHeaderSize +
                                                                        i * tel::kRecordSize);
      old.insert(old.end(), record, record + record_size);
    }
    at += tel::block_size(n);
  }
  hapticd::fuzz::fix_log_crcs(old);
  return old;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_log_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path dir = argv[1];
  fs::create_directories(dir);
  write_seed(dir, "header_only", "", tel::kClockModeRealtime, 0, 512);
  write_seed(dir, "one_record", "loop: {rate_hz: 1000}\n", tel::kClockModeRealtime, 1, 512);
  const fs::path three = write_seed(dir, "three_blocks", "", tel::kClockModeFreerun, 5, 2);
  write_seed(dir, "contact", "wall: {stiffness: 2000}\n", tel::kClockModeFreerun, 6, 6);
  // What a crash leaves: a log cut inside its last block and one cut inside its header.
  const Bytes full = read_bytes(three);
  // How a run's log ends: its counters block after the last records.
  Bytes counted = full;
  for (const std::byte b :
       tel::encode_counters_block(5,
                                  "loop stale_ticks anomaly 3\nloop contact_ticks count 5\nhid "
                                  "short_reports anomaly 1\n")) {
    counted.push_back(static_cast<std::uint8_t>(b));
  }
  expect(tel::read_log_bytes(std::as_bytes(std::span(counted)), "seed").counters.size() == 3,
         "with_counters: the counters block must read back");
  write_bytes(dir / "with_counters.hlog", counted);
  write_bytes(dir / "cut_in_block.hlog", Bytes(full.begin(), full.end() - 30));
  write_bytes(dir / "cut_in_header.hlog", Bytes(full.begin(), full.begin() + 20));
  for (std::uint32_t version : {1u, 2u, 3u}) {
    const std::string name = "v" + std::to_string(version) + "_three_blocks";
    const Bytes old = to_version(full, version);
    expect(blocks_read(old) == blocks_read(full), name + ": an older version's log must read back");
    check_fixer(name, old);
    write_bytes(dir / (name + ".hlog"), old);
  }
  return g_failures == 0 ? 0 : 1;
}
