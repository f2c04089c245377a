#include "sim/sim_device.h"

#include <cerrno>
#include <utility>

#include "base/errno_text.h"
#include "base/hex.h"

namespace hapticd::sim {

std::string_view to_string(PeerFault fault) noexcept {
  switch (fault) {
    case PeerFault::kStopAnswering:
      return "stop answering";
    case PeerFault::kSkipSequence:
      return "skip sequence numbers";
    case PeerFault::kDeviceFault:
      return "report a device fault";
    case PeerFault::kTransportFault:
      return "fail the transport";
  }
  return "unknown fault";
}

SimDevice::SimDevice(const config::DeviceConfig& config, double sample_period_s,
                     std::vector<double> replay_positions)
    : axis_(config, sample_period_s, std::move(replay_positions)) {}

DeviceInfo SimDevice::on_configure() {
  axis_.reset();
  first_read_ = true;
  sequence_ = 0;
  return {"sim (exact plant, in-process)", 0, 0};
}

void SimDevice::on_enable() { axis_.set_output(true); }

void SimDevice::on_disable() noexcept { axis_.set_output(false); }

IoStatus SimDevice::on_read(std::span<PositionSample> samples) noexcept {
  PositionSample& out = samples.front();  // one joint
  if (faults_.active(PeerFault::kTransportFault)) {
    set_fault_code(ENODEV);
    return IoStatus::kTransportFault;
  }
  if (faults_.active(PeerFault::kStopAnswering)) return IoStatus::kNoNewData;
  if (first_read_) {
    first_read_ = false;
  } else {
    axis_.step();
  }
  if (faults_.take(PeerFault::kSkipSequence)) sequence_ += 3;
  out.position = axis_.encoder_position();
  out.sequence = sequence_++;
  out.status = axis_.output_on() ? kStatusOutputEnabled : 0u;
  out.flags = kSampleHasSequence;
  if (faults_.active(PeerFault::kDeviceFault)) {
    out.status |= kStatusFault;
    set_fault_code(kStatusFault);
    return IoStatus::kDeviceFault;
  }
  return IoStatus::kOk;
}

IoStatus SimDevice::on_write(std::span<const double> forces) noexcept {
  const double force = forces.front();  // one joint
  axis_.hold_force(force);
  return IoStatus::kOk;
}

std::string SimDevice::describe(const DeviceFault& fault) const {
  if (fault.fault_class == FaultClass::kDevice) {
    return "sim: the simulated device reported a fault (status " +
           base::hex(fault.code, 1, base::HexCase::kLower) + ")";
  }
  return "sim: the simulated transport failed (" + base::errno_text(static_cast<int>(fault.code)) +
         ")";
}

}  // namespace hapticd::sim
