#include "service/run/direction_report.h"

#include <spdlog/spdlog.h>

#include "gate/number_format.h"

namespace hapticd::service {
namespace {

using control::ProbeState;
using gate::format_number;

std::string mm(double metres) { return format_number(metres * 1e3) + " mm"; }

// "a 0.5 N push": the force the check pushed with.
std::string push(const control::ProbeResult& r) {
  return "a " + format_number(std::abs(r.force)) + " N push";
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
             "or give the push more force or time (safety.direction_check.level, duration_ms); "
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
        push(r), format_number(r.gain), mm(std::abs(r.expected_peak)));
    if (r.latency > 0) {
      // The gate analysed the declared delay: a longer one is a loop it did not prove.
      spdlog::warn(
          "direction check: the device's motion came {} ticks later than its driver declares: "
          "the gate analysed the declared delay; `hapticd check --set wall.delay_samples={}` "
          "says what the longer one allows",
          r.latency, r.latency);
    }
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
          {"latency_ticks", r.latency},
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
      os << "confirmed: " << push(r) << " moved the device " << format_number(r.gain) << " of the "
         << mm(std::abs(r.expected_peak)) << " predicted, the way it pushed\n";
      return;
    case ProbeState::kReversed:
      os << "REVERSED: " << push(r) << " moved the device against it (gain "
         << format_number(r.gain) << "): refused\n";
      return;
    case ProbeState::kNoMotion:
    case ProbeState::kNeverAtRest:
      os << (r.state == ProbeState::kNoMotion ? "NO MOTION under " + push(r)
                                              : std::string("the device was NEVER AT REST"))
         << " (gain " << format_number(r.gain) << " +- " << format_number(r.gain_error)
         << "): " << (refused ? "refused" : "the wall ran UNCHECKED (on_no_motion: run)") << "\n";
      return;
  }
}

}  // namespace hapticd::service
