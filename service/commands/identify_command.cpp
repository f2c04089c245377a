#include "service/commands/identify_command.h"

#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "analysis/free_motion_fit.h"
#include "config/config_loader.h"
#include "gate/number_format.h"
#include "loop/rt_setup.h"
#include "service/commands/identify_run.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "service/run/device_session.h"
#include "service/run/run_support.h"
#include "wiring/registry.h"

namespace hapticd::service {
namespace {

using gate::format_number;

struct Excitation {
  double amplitude = 0.0, f_low = 0.0, f_high = 0.0, duration = 0.0;
  std::vector<double> force;
};

// The joint to excite: --joint, which a device of several joints must be given; its index into
// device.mass and the others. config::ConfigError (exit 2) when wrong or missing.
std::size_t excited_joint(const IdentifyOptions& o, const config::Config& cfg) {
  const int n = kinematics::joint_count(cfg.device.kinematics);
  const std::string has = "device.kinematics (kind " +
                          std::string(kinematics::kind_name(cfg.device.kinematics.kind)) +
                          ") has " + std::to_string(n) + (n == 1 ? " joint" : " joints");
  if (!o.joint && n > 1) {
    throw config::ConfigError({"--joint: " + has + ": say which one to excite (0 to " +
                               std::to_string(n - 1) + "; the others are commanded zero)"});
  }
  const int j = o.joint.value_or(0);
  if (j < 0 || j >= n) {
    throw config::ConfigError({"--joint: must be 0 to " + std::to_string(n - 1) + " (" + has +
                               "), got " + std::to_string(j)});
  }
  return static_cast<std::size_t>(j);
}

// "device.max_force", or "device.max_force[J]" for a joint of several.
std::string key_of(const std::string& key, std::size_t joint, const config::Config& cfg) {
  return kinematics::joint_count(cfg.device.kinematics) == 1
             ? key
             : key + "[" + std::to_string(joint) + "]";
}

// The excitation asked for, checked against the device; config::ConfigError (exit 2) when not.
Excitation plan(const IdentifyOptions& o, const config::Config& cfg, std::size_t j) {
  const double mass = cfg.device.mass[j], damping = cfg.device.damping[j],
               max_force = cfg.device.max_force[j];
  const double rate = cfg.loop.rate_hz, corner = damping / (2.0 * M_PI * mass);
  Excitation e;
  e.duration = o.duration_s;
  // Defaults: enough force that a drive's command resolution (a CiA 402 drive's per mille of
  // rated torque) is small beside it, and a band from the mechanical corner b / (2 pi m), where
  // mass and damping weigh alike, up a decade and more, so the travel stays a few cm.
  e.amplitude = o.amplitude.value_or(0.4 * max_force);
  e.f_high = o.f_high.value_or(std::min(corner * 20.0, rate / 8.0));
  e.f_low = o.f_low.value_or(std::max(std::min(corner, e.f_high / 4.0), 2.0 / e.duration));
  std::vector<std::string> errors;
  const auto bad = [&](bool wrong, const std::string& what) {
    if (wrong) errors.push_back(what);
  };
  bad(!std::isfinite(e.duration) || e.duration < 1.0 || e.duration > 600.0,
      "--duration: must be 1 to 600 s, got " + format_number(e.duration));
  bad(!(e.amplitude > 0.0) || e.amplitude > max_force,
      "--amplitude: must be > 0 and at most " + key_of("device.max_force", j, cfg) + " = " +
          format_number(max_force) + " N, got " + format_number(e.amplitude));
  bad(!(e.f_high < rate / 2.0), "--f-high: must be below the Nyquist frequency " +
                                    format_number(rate / 2.0) + " Hz, got " +
                                    format_number(e.f_high));
  bad(!(e.f_low * e.duration >= 1.0) || !(e.f_low < e.f_high),
      "--f-low: must be at least one cycle over --duration (" + format_number(1.0 / e.duration) +
          " Hz) and below --f-high, got " + format_number(e.f_low));
  bad(!(o.max_travel > 0.0) || !std::isfinite(o.max_travel),
      "--max-travel: must be > 0 m, got " + format_number(o.max_travel));
  if (!errors.empty()) throw config::ConfigError(errors);
  e.force =
      analysis::multisine(e.amplitude, e.f_low, e.f_high, e.duration, cfg.loop.sample_period_s());
  if (!o.amplitude) {
    // Less force where the configured m and b say the default would take the device past half
    // of --max-travel (a light, little damped device moves far at low frequencies).
    double travel = 0.0;
    for (const double x :
         analysis::free_motion_response(e.force, mass, damping, cfg.loop.sample_period_s())) {
      travel = std::max(travel, std::abs(x));
    }
    if (travel > 0.5 * o.max_travel) {
      const double scale = 0.5 * o.max_travel / travel;
      e.amplitude *= scale;
      for (double& u : e.force) u *= scale;
    }
  }
  return e;
}

// Why an excitation that did not run to its end stopped.
std::string describe_end(const ExcitationRecord& rec, const Device& device, double max_travel) {
  switch (rec.end) {
    case ExcitationEnd::kDone:
      return "";
    case ExcitationEnd::kFault:
      return describe_fault(rec.fault, device);
    case ExcitationEnd::kTravel:
      return "the device moved more than --max-travel " + format_number(max_travel) +
             " m from where it started";
    case ExcitationEnd::kStopped:
      return "stopped by a signal";
  }
  return "stopped";
}

// The excitation on this thread, a stop signal watched on another (the tick loop only reads
// an atomic): the one place identify runs the device.
ExcitationRecord excite(Device& device, const Excitation& e, std::size_t joint,
                        const ExcitationLimits& limits, SignalWatch& signals) {
  ExcitationRecord rec(e.force.size(), joint);
  std::atomic<bool> stop{false}, done{false};
  std::thread watch([&] {
    // Not the excitation's real-time priority, which this thread inherits.
    const sched_param normal{};
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
    pollfd fds[2] = {{signals.fd(), POLLIN, 0}, {signals.pipe_fd(), POLLIN, 0}};
    while (!done.load()) {
      poll(fds, 2, 20);
      if (signals.take_pending()) stop.store(true);
    }
  });
  run_excitation(device, e.force, limits, stop, rec);
  done.store(true);
  watch.join();
  return rec;
}

// The encoder's count (m) of a simulated device; 0 when unknown (real hardware).
double count_of(const config::Config& cfg, bool simulated) {
  const double c = cfg.device.sim.counts_per_unit;
  return simulated && c > 0.0 ? 1.0 / c : 0.0;
}

// Said when the fit misses the data by more than a count's quantisation (0.29 counts RMS).
std::string residual_note(const analysis::FreeMotionFit& f, double count) {
  if (count <= 0.0 || f.rms_residual <= 1.5 * count) return "";
  return "the residual (" + format_number(f.rms_residual / count, 3) +
         " counts RMS) is above the encoder's quantisation: something the model leaves out "
         "(the drive's force resolution, friction, compliance) limits the fit, and the "
         "intervals understate the error";
}

// The fit of a reversed force: a negative mass and damping (what the data fit as they are).
double signed_value(const analysis::FreeMotionFit& f, double value) {
  return f.force_reversed ? -value : value;
}

// "device.hid.pid.direction_deg: 270 (it is 90)": the driver's setting that reverses the force.
std::string reversal_fix(const drivers::ForceReversal& r) {
  return r.key + ": " + r.reversed + " (it is " + r.now + ")";
}

nlohmann::json to_json(const analysis::FreeMotionFit& f, const Excitation& e,
                       const config::Config& cfg, std::size_t joint, bool loopback, double travel,
                       double count, const drivers::ForceReversal& reversal) {
  const auto est = [](const analysis::Estimate& x) {
    return nlohmann::json{{"value", x.value}, {"ci95", x.ci95}};
  };
  return {{"schema_version", kIdentifySchemaVersion},
          {"force_direction", f.force_reversed ? "reversed" : "as commanded"},
          {"reverse_with",
           f.force_reversed ? nlohmann::json(reversal_fix(reversal)) : nlohmann::json(nullptr)},
          {"mass", signed_value(f, f.mass.value)},
          {"damping", signed_value(f, f.damping.value)},
          {"mass_ci95", f.mass.ci95},
          {"damping_ci95", f.damping.ci95},
          {"coulomb_friction", f.coulomb_kept ? est(f.coulomb) : nlohmann::json(nullptr)},
          {"delay_samples", f.delay},
          {"rms_residual_m", f.rms_residual},
          {"rms_residual_counts",
           count > 0.0 ? nlohmann::json(f.rms_residual / count) : nlohmann::json(nullptr)},
          {"note", residual_note(f, count)},
          {"joint", joint},
          {"joints", kinematics::joint_count(cfg.device.kinematics)},
          {"samples", f.samples},
          {"ticks", e.force.size()},
          {"travel_m", travel},
          {"driver", cfg.device.driver},
          {"loopback", loopback},
          {"excitation",
           {{"kind", "multisine"},
            {"amplitude", e.amplitude},
            {"f_low", e.f_low},
            {"f_high", e.f_high},
            {"duration_s", e.duration}}}};
}

// What to paste: the fitted value, or for a joint of several the list with the others' as
// configured.
std::string paste(const config::JointValues& configured, double fitted, std::size_t joint,
                  const config::Config& cfg) {
  const auto n = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  if (n == 1) return format_number(fitted, 6);
  std::string list = "[";
  for (std::size_t i = 0; i < n; ++i) {
    list += (i > 0 ? ", " : "") + format_number(i == joint ? fitted : configured[i], 6);
  }
  return list + "]";
}

std::string to_text(const analysis::FreeMotionFit& f, const Excitation& e,
                    const config::Config& cfg, std::size_t joint, bool simulated, double travel,
                    double count, const drivers::ForceReversal& reversal) {
  std::ostringstream os;
  const auto pm = [](const analysis::Estimate& x, int digits) {
    return format_number(x.value, digits) + " +- " + format_number(x.ci95, 2);
  };
  os << "hapticd identify: " << cfg.source_name << " (" << cfg.device.driver
     << (simulated ? ", simulated device held free: no operator" : "")
     << (kinematics::joint_count(cfg.device.kinematics) > 1
             ? ", joint " + std::to_string(joint) + " excited, the others commanded zero"
             : "")
     << ")\n"
     << "  excitation     multisine " << format_number(e.amplitude) << " N peak, "
     << format_number(e.f_low) << " to " << format_number(e.f_high) << " Hz, "
     << format_number(e.duration) << " s (" << e.force.size() << " ticks), travel "
     << format_number(travel * 1e3) << " mm\n";
  if (f.force_reversed) {
    // Nothing to paste: a wall on this device would pull.
    os << "  FORCE REVERSED the device moved against the force: the fit needs a negative mass ("
       << format_number(-f.mass.value, 6) << " kg) and damping ("
       << format_number(-f.damping.value, 6) << " N s/m); a wall would pull\n"
       << "  reverse it     " << cfg.locate(reversal.key) << ": " << reversal_fix(reversal)
       << ", then identify again\n";
    return os.str();
  }
  os << "  force          as commanded (the fit's mass and damping are positive)\n"
     << "  mass m         " << pm(f.mass, 6) << " kg (95 % interval)\n"
     << "  damping b      " << pm(f.damping, 6) << " N s/m\n"
     << "  Coulomb        "
     << (f.coulomb_kept ? pm(f.coulomb, 4) + " N" : std::string("not significant (left out)"))
     << "\n  delay          " << f.delay << " samples between command and force\n"
     << "  residual       " << format_number(f.rms_residual * 1e6, 3) << " um RMS over "
     << f.samples << " samples\n";
  if (const std::string note = residual_note(f, count); !note.empty()) {
    os << "  note           " << note << "\n";
  }
  os << "paste into the configuration:\ndevice:\n  mass: "
     << paste(cfg.device.mass, f.mass.value, joint, cfg)
     << "\n  damping: " << paste(cfg.device.damping, f.damping.value, joint, cfg) << "\n";
  return os.str();
}

}  // namespace

int identify_command(const IdentifyOptions& options, SignalWatch& signals) {
  config::Config cfg = load_config(options.config);
  const std::size_t joint = excited_joint(options, cfg);
  // The sim driver has no hardware device: it only simulates.
  const bool simulated =
      options.loopback || wiring::find_driver(cfg.device.driver).make_device == nullptr;
  if (!simulated && !options.device_free) {
    throw config::ConfigError(
        {"identify drives device." + cfg.device.driver +
         " with a force and no wall: hold nothing, clear its travel, then say so with "
         "--yes-the-device-is-free (or try it with --loopback)"});
  }
  // A simulated device is held free whatever its operator, and runs as fast as it can.
  if (simulated) {
    cfg.device.sim.op = config::OperatorSpec{};
    cfg.device.sim.op.kind = config::OperatorSpec::Kind::kNone;
    cfg.loop.clock = config::ClockMode::kFreerun;
  }
  const bool realtime = !simulated;
  const Excitation e = plan(options, cfg, joint);
  DeviceSession session(cfg, simulated, realtime);
  Device& device = session.device();
  device.configure();
  const int delay = session.driver().declared_delay(cfg);
  loop::RtStatus rt;
  if (realtime) {
    loop::lock_process_memory(rt);
    loop::configure_rt_thread(cfg.loop.rt_priority, cfg.loop.cpu, rt);
    for (const std::string& w : rt.warnings) spdlog::warn("rt: {}", w);
  }
  spdlog::info("identify: exciting {} with up to {} N for {} s", device.info().description,
               format_number(e.amplitude), format_number(e.duration));
  device.enable();
  const ExcitationLimits limits{sample_limits(cfg, device.info(), realtime),
                                cfg.loop.overrun_fault_streak, options.max_travel};
  const ExcitationRecord rec = excite(device, e, joint, limits, signals);
  const std::string why = describe_end(rec, device, options.max_travel);
  session.shut_down();
  if (rec.end != ExcitationEnd::kDone) {
    spdlog::error("identify: {} after {} ticks; zero force commanded, output disabled", why,
                  rec.ticks);
    return kExitRuntimeFault;
  }
  analysis::FreeMotionData data{cfg.loop.sample_period_s(), e.force, rec.position, rec.valid,
                                delay};
  analysis::FreeMotionFit fit;
  try {
    fit = analysis::fit_free_motion(data);
  } catch (const std::invalid_argument& err) {
    spdlog::error("identify: {}", err.what());
    return kExitRuntimeFault;
  }
  const drivers::ForceReversal reversal = session.driver().force_reversal(cfg);
  const double count = count_of(cfg, simulated);
  const std::string text =
      options.json
          ? to_json(fit, e, cfg, joint, options.loopback, rec.travel(), count, reversal).dump(2) +
                "\n"
          : to_text(fit, e, cfg, joint, simulated, rec.travel(), count, reversal);
  if (fit.force_reversed) {
    spdlog::error(
        "identify: the force is reversed (the fit needs a negative mass): no configuration is "
        "printed; reverse it with {}",
        reversal_fix(reversal));
  }
  if (!write_stdout(text)) return kExitRuntimeFault;
  return fit.force_reversed ? kExitRuntimeFault : kExitOk;
}

}  // namespace hapticd::service
