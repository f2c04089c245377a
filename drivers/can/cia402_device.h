// A CiA 402 drive in cyclic synchronous torque (DESIGN.md §6), driven over CANopen.
//
// configure: NMT pre-operational, device type 0x1000 checked for profile 402, the power stage
// switched off (controlword 0x00, "switch on disabled"), rated torque 0x6076 read, mode 10 in
// 0x6060 (read back from 0x6061), 0x1006 communication cycle = T, 0x1017 heartbeat producer,
// 0x6007 the drive's reaction to losing the master, PDOs mapped (or verified) - every SDO
// write confirmed, an abort named with CiA 301's text.
// enable: target torque 0, 0x1016 heartbeat consumer (the drive's own watchdog on hapticd),
// NMT start, then the power state machine walked to Operation enabled through the controlword,
// each step confirmed from the statusword within state_timeout_ms.
// Each tick: read drains the TPDOs, EMCY, heartbeat and bus events; write sends the RPDO
// (controlword 0x0F, target torque in per mille of the rated torque) and then SYNC, at which
// the drive samples its position and applies the torque: the force computed from the sample a
// tick reads acts from the next SYNC on - one sample of delay, declared as such.
// disable: zero torque, controlword 0x06 (shutdown: power stage off), NMT pre-operational,
// the heartbeat consumer switched off. clear_fault: fault reset (0x80 edge), confirmed.
#pragma once

#include <cstdint>
#include <string>

#include "drivers/can/can_device_base.h"
#include "drivers/can/canopen.h"

namespace hapticd::drivers::can {

class Cia402Device final : public CanDeviceBase {
 public:
  Cia402Device(const CanSettings& settings, double sample_period_s, Opener open)
      : CanDeviceBase(settings, sample_period_s, std::move(open)) {}
  ~Cia402Device() override { close(); }

  // Valid from CONFIGURED on: what configure read.
  std::uint32_t rated_torque_mnm() const noexcept { return rated_torque_mnm_; }

 protected:
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_clear_fault() override;
  void on_close() noexcept override { close_transport(); }
  // RT-safe: called every tick.
  IoStatus on_read(PositionSample& out) noexcept override;
  // RT-safe: called every tick.
  IoStatus on_write(double force) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  void on_frame(const CanSocket::Received& rx) noexcept override;
  std::string describe_cause(const DeviceFault& fault) const;
  void on_tpdo1(const CanSocket::Received& rx) noexcept;
  void on_emcy(const CanFrame& f) noexcept;

  // SDO client (non-RT): expedited transfers, each answered within sdo_timeout_ms.
  std::uint32_t sdo_read(canopen::SdoAddress at, const char* name);
  void sdo_write(canopen::SdoAddress at, std::uint32_t value, std::uint8_t size, const char* name);
  canopen::SdoReply sdo_exchange(const CanFrame& request, canopen::SdoAddress at, const char* name);
  // Frames that arrive while configuring or enabling: an EMCY ends it with a DeviceError.
  void note_async(const CanFrame& f);
  std::string sdo_where(canopen::SdoAddress at, const char* name) const;

  void switch_off_and_identify();
  void write_parameters();
  void map_pdos();
  void walk_to_enabled();
  cia402::PowerState read_state(std::uint16_t& statusword);
  std::string drive_error_text();

  std::uint32_t rated_torque_mnm_ = 0;
  double permille_per_force_ = 0.0;  // per mille of rated torque per N (or N m) of axis force
  int max_permille_ = 0;             // max_torque in per mille
  std::uint32_t master_heartbeat_ticks_ = 0;
  std::uint32_t tick_ = 0;

  // RT state of the newest sample.
  bool fresh_ = false;
  std::uint16_t statusword_ = 0;
  std::int32_t position_ = 0;
  std::int32_t velocity_ = 0;
  std::int64_t sample_time_ns_ = 0;
};

}  // namespace hapticd::drivers::can
