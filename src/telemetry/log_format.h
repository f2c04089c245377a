// The binary tick log, format version 5. Everything is little-endian, with no padding and
// no alignment between fields; offsets below are in bytes. Versions 1 to 4 differ only in
// their records: 72, 96, 112 and 176 bytes, the first bytes of version 5's (record_size says
// which), and version 4 has no marker 4.
//
// File header (44 + config_len bytes):
//   0   u8[8]  magic "HAPTLOG\0" (48 41 50 54 4C 4F 47 00)
//   8   u32    version = 5 (1 to 4 are still read)
//   12  u32    record_size = 200 (72, 96, 112 and 176 in versions 1 to 4)
//   16  f64    sample_period_s (IEEE-754 binary64)
//   24  i64    start_unix_ns: wall-clock time of tick 0 in ns since the Unix epoch, 0 = unknown
//   32  u32    clock_mode: 0 = realtime, 1 = freerun
//   36  u32    config_len (at most kMaxConfigBytes)
//   40  u8[config_len]  the whole effective configuration as UTF-8 YAML (not NUL-terminated)
//   40+config_len  u32  CRC-32 of bytes [0, 40+config_len)
//
// Then zero or more blocks, back to back until the end of the file. Block (28 + 200*n bytes):
//   0   u8[4]  magic "HBLK" (48 42 4C 4B)
//   4   u32    record_count n, 0..kMaxBlockRecords
//   8   u64    first_tick: the tick of the first record. In a block with n = 0 it is the tick
//              after the last record before the loss (0 if none); informational only.
//   16  u64    dropped_before: records the RT ring dropped (or that failed to reach the
//              disk) between the previous block's last record and this block's first one.
//              A block with n = 0 and dropped_before > 0 is a pure loss marker.
//   24  u32    CRC-32 of block bytes [0, 24) followed by the n*200 record bytes
//   28  n records of 200 bytes:
//        0 u64 tick, 8 i64 scheduled_ns, 16 i32 wake_latency_ns, 20 i32 compute_ns,
//        24 f64 position, 32 f64 penetration, 40 f64 velocity, 48 f64 force_computed,
//        56 f64 force_commanded, 64 u32 flags (TickFlag bits), 68 u32 device_status,
//        72 i64 sample_time_ns, 80 u32 sequence, 84 u8 fault_cause, 85 u8 fault_class,
//        86 u16 sequence_gap, 88 u32 fault_code, 92 u32 marker (TickMarker: 0 for a tick,
//        1 reload accepted, 2 reload refused, 3 re-armed after a cleared fault, 4 a client
//        moved a wall (version 5): an event at a tick boundary, not a tick), 96 f64
//        observer_energy_j (the passivity observer's energy, J), 104 f64 passivity_damping (N s/m
//        the passivity controller added), version 4 (a device of several joints; zero for one): 112
//        f64[2] joint_position (joints 2 and 3; position is joint 1's), 128 f64[2] joint_force
//        (likewise force_commanded), 144 f64[3] task_position (m), 168 u8 joints (0: one), 169 u8
//        deepest_wall (penetration, velocity and force_computed are that wall's), 170 u8
//        wall_contact (bit per wall), 171 u8 pose_status (0 ok, 1 outside workspace, 2 near
//        singularity, 3 no convergence), 172 u32 reserved (0),
//        version 5: 176 f64[3] client_force (a client's servo_cf this tick, task space, N);
//        a marker 1 of several joints has in `sequence` which running wall each new one went
//        on from (telemetry::continues_code)
//
// A live reload that swapped a new control law in (marker 1), and a re-arming (marker 3, a
// law started afresh), add a config block right after the block holding their marker record,
// so a reader knows the law from that tick on. Config block (28 + len bytes):
//   0   u8[4]  magic "HCFG" (48 43 46 47)
//   4   u32    len: bytes of configuration text, at most kMaxConfigBytes
//   8   u64    first_tick: the first tick the new configuration governs
//   16  u64    0
//   24  u32    CRC-32 of bytes [0, 24) followed by the text
//   28  u8[len]  the new effective configuration as UTF-8 YAML
//
// When the run ends, the writer adds a counters block: the run's counter registry
// (docs/operations.md#counters), the loop's and the driver's, as they stood when output was
// disabled. Readers that predate it see trailing bytes they skip. Counters block
// (28 + len bytes), the config block's layout with:
//   0   u8[4]  magic "HCNT" (48 43 4E 54)
//   8   u64    first_tick: the tick after the last record
//   28  u8[len]  one line per counter, "SOURCE NAME KIND VALUE\n" (KIND "count" or
//                "anomaly", VALUE decimal), in the registry's order
//
// CRC-32 is the common one (zlib crc32, Python zlib.crc32: reflected polynomial 0xEDB88320,
// initial value and final xor 0xFFFFFFFF). A reader accepts blocks in order; a block that is
// incomplete or fails its checks is skipped up to the next "HBLK" whose block is complete and
// CRC-valid (a damaged stretch in the middle), and when none follows, reading ends there
// (what a log cut short by a crash looks like).
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "telemetry/tick_record.h"

namespace hapticd::telemetry {

// Records are copied to and from the file as raw bytes, which is the little-endian layout
// only on a little-endian host.
static_assert(std::endian::native == std::endian::little, "the tick log is little-endian");

// Field-by-field loads and stores at explicit offsets: the layout never depends on struct
// padding.
template <typename V>
void store_field(std::byte* at, V value) noexcept {
  static_assert(std::is_trivially_copyable_v<V>);
  std::memcpy(at, &value, sizeof(V));
}
template <typename V>
V load_field(const std::byte* at) noexcept {
  V value;
  std::memcpy(&value, at, sizeof(V));
  return value;
}

inline constexpr std::array<char, 8> kFileMagic = {'H', 'A', 'P', 'T', 'L', 'O', 'G', '\0'};
inline constexpr std::uint32_t kFormatVersion = 5;
inline constexpr std::uint32_t kRecordSize = 200;
inline constexpr std::uint32_t kRecordSizeV4 = 176;      // version 4: the first 176 bytes
inline constexpr std::uint32_t kRecordSizeV1 = 72;       // version 1: the first 72 bytes
inline constexpr std::uint32_t kRecordSizeV2 = 96;       // version 2: the first 96 bytes
inline constexpr std::uint32_t kRecordSizeV3 = 112;      // version 3: the first 112 bytes
inline constexpr std::size_t kFileHeaderFixedSize = 40;  // bytes before the config text
inline constexpr std::size_t kCrcSize = 4;
inline constexpr std::uint32_t kMaxConfigBytes = 16u << 20;  // a sanity bound, not a YAML limit

inline constexpr std::array<char, 4> kBlockMagic = {'H', 'B', 'L', 'K'};
inline constexpr std::array<char, 4> kConfigMagic = {'H', 'C', 'F', 'G'};
inline constexpr std::array<char, 4> kCountersMagic = {'H', 'C', 'N', 'T'};
inline constexpr std::size_t kBlockHeaderSize = 28;
inline constexpr std::size_t kBlockCrcOffset = 24;
inline constexpr std::uint32_t kMaxBlockRecords = 65536;

inline constexpr std::uint32_t kClockModeRealtime = 0;
inline constexpr std::uint32_t kClockModeFreerun = 1;

// The record layout documented above; a change here is a new format version.
static_assert(sizeof(TickRecord) == kRecordSize);
static_assert(
    offsetof(TickRecord, scheduled_ns) == 8 && offsetof(TickRecord, wake_latency_ns) == 16 &&
    offsetof(TickRecord, compute_ns) == 20 && offsetof(TickRecord, position) == 24 &&
    offsetof(TickRecord, penetration) == 32 && offsetof(TickRecord, velocity) == 40 &&
    offsetof(TickRecord, force_computed) == 48 && offsetof(TickRecord, force_commanded) == 56 &&
    offsetof(TickRecord, flags) == 64 && offsetof(TickRecord, device_status) == 68 &&
    offsetof(TickRecord, sample_time_ns) == 72 && offsetof(TickRecord, sequence) == 80 &&
    offsetof(TickRecord, fault_cause) == 84 && offsetof(TickRecord, fault_class) == 85 &&
    offsetof(TickRecord, sequence_gap) == 86 && offsetof(TickRecord, fault_code) == 88 &&
    offsetof(TickRecord, marker) == 92 && offsetof(TickRecord, observer_energy_j) == 96 &&
    offsetof(TickRecord, passivity_damping) == 104 && offsetof(TickRecord, joint_position) == 112 &&
    offsetof(TickRecord, joint_force) == 128 && offsetof(TickRecord, task_position) == 144 &&
    offsetof(TickRecord, joints) == 168 && offsetof(TickRecord, deepest_wall) == 169 &&
    offsetof(TickRecord, wall_contact) == 170 && offsetof(TickRecord, pose_status) == 171 &&
    offsetof(TickRecord, reserved) == 172 && offsetof(TickRecord, client_force) == 176);

// What the file header carries besides the constants.
struct LogHeader {
  double sample_period_s = 0.0;
  std::int64_t start_unix_ns = 0;
  std::uint32_t clock_mode = kClockModeRealtime;
  std::string config_text;
};

// The fields of one block header, decoded.
struct BlockHeader {
  std::uint32_t record_count = 0;
  std::uint64_t first_tick = 0;
  std::uint64_t dropped_before = 0;
  std::uint32_t crc = 0;
};

// The record size of a format version, 0 for a version this reader does not know.
constexpr std::size_t record_size_of_version(std::uint32_t version) {
  return version == 1                ? kRecordSizeV1
         : version == 2              ? kRecordSizeV2
         : version == 3              ? kRecordSizeV3
         : version == 4              ? kRecordSizeV4
         : version == kFormatVersion ? kRecordSize
                                     : 0;
}

constexpr std::size_t file_header_size(std::size_t config_len) {
  return kFileHeaderFixedSize + config_len + kCrcSize;
}
constexpr std::size_t block_size(std::size_t record_count, std::size_t record_size = kRecordSize) {
  return kBlockHeaderSize + record_count * record_size;
}

// CRC-32 (zlib) of bytes, continuing from crc (start with 0).
std::uint32_t crc32_update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept;

// The complete file header. Throws std::invalid_argument when the config text is longer
// than kMaxConfigBytes.
std::vector<std::byte> encode_file_header(const LogHeader& header);

// Encodes one block (header, CRC and records) into out and returns its size. Returns 0 and
// writes nothing when out is smaller than block_size(records.size()) or when there are more
// than kMaxBlockRecords records. Does not allocate.
std::size_t encode_block(std::span<std::byte> out, std::uint64_t first_tick,
                         std::uint64_t dropped_before,
                         std::span<const TickRecord> records) noexcept;

// A config block (layout above). Not RT-safe (allocates). Throws std::invalid_argument when
// the text is longer than kMaxConfigBytes.
std::vector<std::byte> encode_config_block(std::uint64_t first_tick, std::string_view text);
// A counters block (layout above), the same way.
std::vector<std::byte> encode_counters_block(std::uint64_t first_tick, std::string_view text);

// Decodes the 28-byte block header at the start of bytes (which must hold at least
// kBlockHeaderSize bytes, else all fields are 0). The magic is not checked here.
BlockHeader decode_block_header(std::span<const std::byte> bytes) noexcept;

}  // namespace hapticd::telemetry
