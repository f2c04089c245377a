// The byte layout of the tick log, checked against the documented offsets with zlib's CRC
// computed here, so a reader written from log_format.h alone would agree with the writer.
#include "telemetry/log_format.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "telemetry/log_writer.h"
#include "telemetry_test_util.h"

namespace hapticd::telemetry {
namespace {

using test::make_records;
using test::sample_header;

template <typename V>
V at(const std::vector<std::byte>& bytes, std::size_t offset) {
  V v;
  std::memcpy(&v, bytes.data() + offset, sizeof(V));
  return v;
}

std::uint32_t zlib_crc(const std::vector<std::byte>& bytes, std::size_t from, std::size_t n,
                       std::uint32_t crc = 0) {
  return static_cast<std::uint32_t>(
      ::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + from), static_cast<uInt>(n)));
}

TEST(LogFormat, FileMatchesTheDocumentedLayout) {
  test::TempDir dir;
  const std::string path = dir.file("layout.htl");
  const LogHeader header = sample_header();
  const std::vector<TickRecord> records = make_records(40, 5);
  write_log_file(path, header, records, 3);  // blocks of 3 and 2
  const std::vector<std::byte> b = test::read_bytes(path);

  const std::size_t len = header.config_text.size();
  const std::size_t header_size = 44 + len;
  const std::size_t block0 = header_size, block1 = block0 + 28 + 3 * kRecordSize;
  ASSERT_EQ(b.size(), block1 + 28 + 2 * kRecordSize);

  EXPECT_EQ(std::memcmp(b.data(), "HAPTLOG\0", 8), 0);
  EXPECT_EQ(at<std::uint32_t>(b, 8), 5u);
  EXPECT_EQ(at<std::uint32_t>(b, 12), 200u);
  EXPECT_EQ(at<double>(b, 16), header.sample_period_s);
  EXPECT_EQ(at<std::int64_t>(b, 24), header.start_unix_ns);
  EXPECT_EQ(at<std::uint32_t>(b, 32), 1u);  // freerun
  EXPECT_EQ(at<std::uint32_t>(b, 36), len);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.data()) + 40, len), header.config_text);
  EXPECT_EQ(at<std::uint32_t>(b, 40 + len), zlib_crc(b, 0, 40 + len));

  const std::size_t starts[] = {block0, block1};
  const std::uint32_t counts[] = {3, 2};
  for (int k = 0; k < 2; ++k) {
    const std::size_t o = starts[k];
    const std::uint32_t n = counts[k];
    EXPECT_EQ(std::memcmp(b.data() + o, "HBLK", 4), 0);
    EXPECT_EQ(at<std::uint32_t>(b, o + 4), n);
    EXPECT_EQ(at<std::uint64_t>(b, o + 8), records[k * 3].tick);  // first_tick
    EXPECT_EQ(at<std::uint64_t>(b, o + 16), 0u);                  // dropped_before
    const std::uint32_t crc = zlib_crc(b, o + 28, n * kRecordSize, zlib_crc(b, o, 24));
    EXPECT_EQ(at<std::uint32_t>(b, o + 24), crc) << "block " << k;
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::size_t r = o + 28 + i * kRecordSize;
      const TickRecord& want = records[k * 3 + i];
      // A few fields at their documented offsets, then the whole record bytewise.
      EXPECT_EQ(at<std::uint64_t>(b, r + 0), want.tick);
      EXPECT_EQ(at<std::int32_t>(b, r + 16), want.wake_latency_ns);
      EXPECT_EQ(at<double>(b, r + 24), want.position);
      EXPECT_EQ(at<double>(b, r + 56), want.force_commanded);
      EXPECT_EQ(at<std::uint32_t>(b, r + 68), want.device_status);
      EXPECT_EQ(at<std::int64_t>(b, r + 72), want.sample_time_ns);
      EXPECT_EQ(at<std::uint32_t>(b, r + 80), want.sequence);
      EXPECT_EQ(at<std::uint8_t>(b, r + 84), want.fault_cause);
      EXPECT_EQ(at<std::uint16_t>(b, r + 86), want.sequence_gap);
      EXPECT_EQ(at<std::uint32_t>(b, r + 88), want.fault_code);
      EXPECT_EQ(at<double>(b, r + 96), want.observer_energy_j);
      EXPECT_EQ(at<double>(b, r + 104), want.passivity_damping);
      EXPECT_EQ(at<double>(b, r + 112), want.joint_position[0]);
      EXPECT_EQ(at<double>(b, r + 136), want.joint_force[1]);
      EXPECT_EQ(at<double>(b, r + 160), want.task_position[2]);
      EXPECT_EQ(at<std::uint8_t>(b, r + 168), want.joints);
      EXPECT_EQ(at<std::uint8_t>(b, r + 170), want.wall_contact);
      EXPECT_EQ(at<std::uint8_t>(b, r + 171), want.pose_status);
      EXPECT_EQ(at<double>(b, r + 192), want.client_force[2]);
      EXPECT_EQ(std::memcmp(b.data() + r, &want, kRecordSize), 0);
    }
  }
}

TEST(LogFormat, EncodeBlockRefusesABufferTooSmall) {
  const std::vector<TickRecord> records = make_records(0, 2);
  std::vector<std::byte> buf(block_size(2) - 1, std::byte{0x5a});
  EXPECT_EQ(encode_block(buf, 0, 0, records), 0u);
  for (std::byte v : buf) ASSERT_EQ(v, std::byte{0x5a}) << "nothing may be written";
  buf.resize(block_size(2));
  EXPECT_EQ(encode_block(buf, 0, 0, records), block_size(2));
}

TEST(LogFormat, LossMarkerBlockHasNoRecords) {
  std::vector<std::byte> buf(block_size(0));
  ASSERT_EQ(encode_block(buf, 77, 12, {}), 28u);
  const BlockHeader h = decode_block_header(buf);
  EXPECT_EQ(h.record_count, 0u);
  EXPECT_EQ(h.first_tick, 77u);
  EXPECT_EQ(h.dropped_before, 12u);
  EXPECT_EQ(h.crc,
            static_cast<std::uint32_t>(::crc32(0, reinterpret_cast<const Bytef*>(buf.data()), 24)));
}

TEST(LogFormat, OversizedConfigurationIsRejectedBeforeAnythingIsWritten) {
  test::TempDir dir;
  LogHeader header = sample_header();
  header.config_text.assign(kMaxConfigBytes + 1, 'x');
  EXPECT_THROW(encode_file_header(header), std::invalid_argument);
  const std::string path = dir.file("big.htl");
  EXPECT_THROW(write_log_file(path, header, {}), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace hapticd::telemetry
