#include "sim/sim_device.h"

#include <cerrno>
#include <string>
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
    : axis_(config, sample_period_s, std::move(replay_positions)) {
  if (kinematics::joint_count(config.kinematics) > 1) {
    joints_ = std::make_unique<Mechanism>(config, sample_period_s);
  }
}

DeviceInfo SimDevice::on_configure() {
  axis_.reset();
  if (joints_) joints_->reset();
  first_read_ = true;
  sequence_ = 0;
  if (joints_) {
    return {"sim (" + std::to_string(joints_->joints()) + " joints, in-process)", 0, 0,
            static_cast<std::size_t>(joints_->joints())};
  }
  return {"sim (exact plant, in-process)", 0, 0};
}

void SimDevice::on_enable() {
  axis_.set_output(true);
  output_on_ = true;
  for (int i = 0; joints_ && i < joints_->joints(); ++i) joints_->set_output(i, true);
}

void SimDevice::on_disable() noexcept {
  axis_.set_output(false);
  output_on_ = false;
  for (int i = 0; joints_ && i < joints_->joints(); ++i) joints_->set_output(i, false);
}

IoStatus SimDevice::read_joints(std::span<PositionSample> samples) noexcept {
  if (faults_.active(PeerFault::kTransportFault)) {
    set_fault_code(ENODEV);
    return IoStatus::kTransportFault;
  }
  if (faults_.active(PeerFault::kStopAnswering)) return IoStatus::kNoNewData;
  for (std::uint32_t k = 0; !first_read_ && k < read_periods(); ++k) joints_->step();
  first_read_ = false;
  if (faults_.take(PeerFault::kSkipSequence)) sequence_ += 3;
  const bool fault = faults_.active(PeerFault::kDeviceFault);
  for (std::size_t i = 0; i < samples.size(); ++i) {  // every joint at the same instant
    PositionSample& out = samples[i];
    out.position = joints_->encoder_position(static_cast<int>(i));
    out.sequence = sequence_;
    out.status = (output_on_ ? kStatusOutputEnabled : 0u) | (fault ? kStatusFault : 0u);
    out.flags = kSampleHasSequence;
  }
  ++sequence_;
  if (!fault) return IoStatus::kOk;
  set_fault_code(kStatusFault);
  return IoStatus::kDeviceFault;
}

IoStatus SimDevice::on_read(std::span<PositionSample> samples) noexcept {
  if (joints_) return read_joints(samples);
  PositionSample& out = samples.front();  // one joint
  if (faults_.active(PeerFault::kTransportFault)) {
    set_fault_code(ENODEV);
    return IoStatus::kTransportFault;
  }
  if (faults_.active(PeerFault::kStopAnswering)) return IoStatus::kNoNewData;
  for (std::uint32_t k = 0; !first_read_ && k < read_periods(); ++k) axis_.step();
  first_read_ = false;
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
  if (joints_) {
    for (std::size_t i = 0; i < forces.size(); ++i) {
      joints_->hold_torque(static_cast<int>(i), forces[i]);
    }
  } else {
    axis_.hold_force(forces.front());  // one joint
  }
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
