#include "service/run/direction_report.h"

#include <spdlog/spdlog.h>

#include "gate/number_format.h"

namespace hapticd::service {
namespace {

using control::ProbeState;
using gate::format_number;

std::string mm(double metres) { return format_number(metres * 1e3) + " mm"; }

// "a 0.5 N pulse": the force the check pushed with first.
std::string pulse(const control::ProbeResult& r) {
  return "a " + format_number(std::abs(r.force)) + " N pulse";
}

// The wall ran with a direction nobody has checked.
bool unchecked(const control::ProbeResult& r) {
  return r.state == ProbeState::kNoMotion || r.state == ProbeState::kNeverAtRest;
}

}  // namespace

std::string direction_advice(loop::FaultCause cause, const config::Config& cfg,
                             const wiring::DriverEntry& driver) {
  using loop::FaultCause;
  switch (cause) {
    case FaultCause::kForceReversed: {
      if (driver.force_reversal == nullptr) return "";
      const drivers::ForceReversal f = driver.force_reversal(cfg);
      return ". Reverse the force with " + cfg.locate(f.key) + ": " + f.key + ": " + f.reversed +
             " (it is " + f.now + "), then check and run again";
    }
    case FaultCause::kNoProbeMotion:
      return ". Let go of the device while it starts (the check takes a fraction of a second), "
             "or give the pulse more force or time (safety.direction_check.level, duration_ms); "
             "safety.direction_check.on_no_motion: run arms the wall unchecked";
    case FaultCause::kNeverAtRest:
      return ". Hold the device still or let go of it while it starts, or allow longer "
             "(safety.direction_check.rest_timeout_ms); safety.direction_check.on_no_motion: run "
             "arms the wall unchecked";
    default:
      return "";
  }
}

void announce_direction(const control::ProbeResult& r) {
  if (r.state == ProbeState::kConfirmed) {
    spdlog::info(
        "direction check: confirmed: {} moved the device {} of the {} the configured mass and "
        "damping predict, the way it pushed",
        pulse(r), format_number(r.gain), mm(std::abs(r.expected_peak)));
  } else if (unchecked(r)) {
    spdlog::warn(
        "direction check: {} (gain {} +- {}): the wall is armed UNCHECKED "
        "(safety.direction_check.on_no_motion: run); the runaway guard still stops a wall "
        "that pulls",
        control::probe_state_name(r.state), format_number(r.gain), format_number(r.gain_error));
  }
}

nlohmann::json direction_json(const control::ProbeResult& r) {
  return {{"state", control::probe_state_name(r.state)},
          {"gain", r.gain},
          {"gain_error", r.gain_error},
          {"force", r.force},
          {"expected_motion", r.expected_peak},
          {"ticks", r.ticks},
          {"unchecked", r.state != ProbeState::kConfirmed}};
}

void direction_text(const control::ProbeResult& r, bool refused, std::ostream& os) {
  os << "  direction      ";
  switch (r.state) {
    case ProbeState::kOff:
      os << "not checked (safety.direction_check.mode: off)\n";
      return;
    case ProbeState::kWaiting:
    case ProbeState::kPulsing:
      os << "not finished: the run ended during the check\n";
      return;
    case ProbeState::kConfirmed:
      os << "confirmed: " << pulse(r) << " moved the device " << format_number(r.gain) << " of the "
         << mm(std::abs(r.expected_peak)) << " predicted, the way it pushed\n";
      return;
    case ProbeState::kReversed:
      os << "REVERSED: " << pulse(r) << " moved the device against it (gain "
         << format_number(r.gain) << "): refused\n";
      return;
    case ProbeState::kNoMotion:
    case ProbeState::kNeverAtRest:
      os << (r.state == ProbeState::kNoMotion ? "NO MOTION under " + pulse(r)
                                              : std::string("the device was NEVER AT REST"))
         << " (gain " << format_number(r.gain) << " +- " << format_number(r.gain_error)
         << "): " << (refused ? "refused" : "the wall ran UNCHECKED (on_no_motion: run)") << "\n";
      return;
  }
}

}  // namespace hapticd::service
