// The ODrive axes of one bus (odrive_profile.h): the lifecycle through every axis, and each
// tick every axis's frames (its torque, its own request for its position).
#include "drivers/can/odrive_profile.h"

namespace hapticd::drivers::can {

std::unique_ptr<CanProfile> make_odrive_profile(const CanSettings& s, double sample_period_s,
                                                CanLink& link) {
  return std::make_unique<OdriveProfile>(s, sample_period_s, link);
}

OdriveProfile::OdriveProfile(const CanSettings& settings, double sample_period_s, CanLink& link)
    : settings_(settings), link_(link) {
  for (const CanNode& n : settings_.nodes) {
    axes_.push_back(std::make_unique<OdriveAxis>(settings_, n, sample_period_s, link_));
  }
}

DeviceInfo OdriveProfile::configure() {
  DeviceInfo info;
  std::array<CanFrame, 2 * base::kMaxJoints> stop{};
  std::size_t n = 0;
  for (const auto& axis : axes_) {
    const DeviceInfo one = axis->configure();
    info.description += (info.description.empty() ? "" : "; ") + one.description;
    info.transport_delay_samples = one.transport_delay_samples;  // the same for every axis
    for (const CanFrame& f : axis->emergency_frames()) stop[n++] = f;
  }
  info.joints = axes_.size();
  link_.set_emergency_frames({stop.data(), n});
  return info;
}

void OdriveProfile::enable() {
  for (const auto& axis : axes_) axis->enable();  // a failure: disable idles every axis
  for (const auto& axis : axes_) axis->stop_feeding();
}

void OdriveProfile::disable(const CanFault& latched) noexcept {
  std::array<bool, base::kMaxJoints> now{};
  for (std::size_t i = 0; i < axes_.size(); ++i) now[i] = axes_[i]->stop_output();
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    // Only the axis that reported the fault is asked why.
    const CanFault own = latched.joint == i ? latched : CanFault{};
    axes_[i]->after_stop(own, now[i]);
  }
}

void OdriveProfile::clear_fault() {
  for (const auto& axis : axes_) axis->clear_fault();
}

void OdriveProfile::close() noexcept {
  for (const auto& axis : axes_) axis->close();
}

std::vector<std::string> OdriveProfile::notices() const {
  std::vector<std::string> all;
  for (const auto& axis : axes_) {
    all.insert(all.end(), axis->notices().begin(), axis->notices().end());
  }
  return all;
}

FrameMeaning OdriveProfile::on_frame(const CanSocket::Received& rx, bool active) noexcept {
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    if (!axes_[i]->owns(rx.frame)) continue;
    FrameMeaning m = axes_[i]->on_frame(rx, active);
    m.joint = static_cast<std::uint8_t>(i);
    m.fault.joint = m.joint;
    return m;
  }
  link_.count(CanCounter::kUnknownIds);
  return {};
}

void OdriveProfile::sample(std::size_t joint, PositionSample& out) const noexcept {
  axes_[joint]->sample(out);
}

std::span<const CanFrame> OdriveProfile::tick_frames(std::span<const double> forces) noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    for (const CanFrame& f : axes_[i]->tick_frames(forces[i])) tx_[n++] = f;
  }
  return {tx_.data(), n};
}

std::string OdriveProfile::describe(const CanFault& fault, const std::string& bus) const {
  return axes_[fault.joint]->describe(fault, bus);
}

}  // namespace hapticd::drivers::can
