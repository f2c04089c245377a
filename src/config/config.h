// Typed, validated configuration of hapticd. Plain values in SI units; every field has the
// default the daemon uses when the YAML leaves it out. Parsing and validation live in
// config_loader.h; nothing here knows about YAML.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "base/joints.h"
#include "kinematics/kinematics.h"

namespace hapticd::config {

enum class ClockMode { kRealtime, kFreerun };
enum class Discretization { kBackward, kTustin };
// enforce: refuse a failing gate; warn: run anyway, loudly; derate: run with the largest
// stiffness that passes (the gate's max_stiffness), loudly, or refuse when none does.
enum class GateMode { kEnforce, kWarn, kDerate };
// The runtime passivity observer (control/passivity_observer.h): off; observe (energy logged);
// damp (also the passivity controller: damping that dissipates a negative energy).
enum class PassivityControl { kOff, kObserve, kDamp };

// Polynomial coefficients in ascending powers of z^-1: {a0, a1, ...} means a0 + a1 z^-1 + ...
using Coefficients = std::vector<double>;

// Longest coupling numerator/denominator: the controller's filter histories are fixed-size so
// the RT thread never allocates (a power of two: the histories index with a mask).
inline constexpr std::size_t kMaxCouplingCoefficients = 16;
// wall.delay_samples: the gate analyses the delayed loop in well under a second up to here.
inline constexpr int kMaxDelaySamples = 100;
// telemetry.ring_capacity: records preallocated and locked between the loop and the writer.
inline constexpr long long kMaxRingCapacity = 1LL << 22;

// T in seconds for a period of whole nanoseconds.
constexpr double period_s(std::int64_t period_ns) { return static_cast<double>(period_ns) / 1e9; }

struct LoopConfig {
  double rate_hz = 1000.0;  // sample rate 1/T (Hz), in [1, 100000]
  ClockMode clock = ClockMode::kRealtime;
  int rt_priority = 80;           // SCHED_FIFO priority, 1..99
  int cpu = -1;                   // CPU the RT thread is pinned to; -1 = not pinned
  int overrun_fault_streak = 10;  // consecutive overruns that fault the loop, >= 1

  // The sample period, defined once: the loop sleeps whole nanoseconds, so T is the rate's
  // period rounded to the nanosecond, and every model (controller, gate, observer, plant)
  // computes with that T. For a rate that divides 1e9 it is 1/rate to the last bit.
  std::int64_t period_ns() const { return std::llround(1e9 / rate_hz); }
  double sample_period_s() const;
};

inline double LoopConfig::sample_period_s() const { return period_s(period_ns()); }

// A time profile used for the hand's set-point (m) and the force operator (N).
// constant/step/ramp/press are stored as breakpoints of a piecewise-linear function
// (held constant before the first and after the last point; two points at the same time
// make a jump); sine is offset + amplitude * sin(2 pi f t + phase).
struct ProfilePoint {
  double t_s = 0.0;
  double value = 0.0;
  friend bool operator==(const ProfilePoint&, const ProfilePoint&) = default;
};
struct ProfileSpec {
  enum class Shape { kConstant, kStep, kRamp, kSine, kPress };
  Shape shape = Shape::kConstant;
  std::vector<ProfilePoint> points;  // all shapes but sine
  double offset = 0.0;               // sine only
  double amplitude = 0.0;            // sine only
  double frequency_hz = 0.0;         // sine only
  double phase_rad = 0.0;            // sine only
  friend bool operator==(const ProfileSpec&, const ProfileSpec&) = default;
};

// Imposed motion: positions at the sample instants are offset + amplitude*cos(2 pi f t + phase);
// between samples the position is linear (constant velocity inside each period).
struct MotionSpec {
  double offset = 0.0;
  double amplitude = 0.0;
  double frequency_hz = 1.0;
  double phase_rad = 0.0;
  friend bool operator==(const MotionSpec&, const MotionSpec&) = default;
};

struct OperatorSpec {
  enum class Kind { kNone, kHand, kForce, kMotion, kReplay };
  Kind kind = Kind::kHand;
  double stiffness = 300.0;  // hand: k_h (N/m), > 0
  double damping = 5.0;      // hand: b_h (N s/m), >= 0; acts against the device velocity
  ProfileSpec setpoint;      // hand: set-point (m); its spring force is the bias force
  ProfileSpec force;         // force: operator force (N)
  MotionSpec motion;         // motion
  std::string replay_log;    // replay: tick log whose positions are imposed (absolute path)
  // hand or none, on a device of several task axes (docs/kinematics.md, the simulated
  // mechanism): the device starts at rest at `origin` (m; the workspace's centre by default),
  // and the hand's set-point is origin + setpoint(t) direction (unit, normalised as read).
  kinematics::Vec3 origin = kinematics::Vec3::Zero();
  kinematics::Vec3 direction = kinematics::Vec3::Zero();
  friend bool operator==(const OperatorSpec&, const OperatorSpec&) = default;
};

struct SimDeviceConfig {
  double counts_per_unit = 1.0e5;  // encoder resolution (counts per m); 0 = ideal encoder
  double noise_counts = 0.0;       // std dev of Gaussian encoder noise in counts; 0 = off
  std::uint64_t seed = 1;          // seed of the encoder noise
  double initial_position = 0.0;   // m
  double initial_velocity = 0.0;   // m/s
  // The simulated motor pushes against the force commanded (a motor wired the other way
  // round): what the direction check and the runaway guard are for (docs/devices.md).
  bool force_reversed = false;
  OperatorSpec op;
  friend bool operator==(const SimDeviceConfig&, const SimDeviceConfig&) = default;
};

// A driver's own settings, the section device.<driver>: parsed and validated by the driver's
// code (config/driver_schema.h), carried here without the config library knowing them.
struct DriverSettings {
  virtual ~DriverSettings() = default;
};

// device.mass, damping, max_force: one number for every joint, or a list of one per joint (as
// long as device.kinematics has joints). A device of one joint reads joint 0.
class JointValues {
 public:
  JointValues(double every) noexcept { values_.fill(every); }  // one number: every joint
  double operator[](std::size_t joint) const noexcept { return values_[joint]; }
  double& operator[](std::size_t joint) noexcept { return values_[joint]; }
  // Every joint's, in joint order (the joints a device does not have hold what they held).
  kinematics::Vec3 per_joint() const noexcept { return {values_[0], values_[1], values_[2]}; }
  bool operator==(const JointValues&) const = default;

 private:
  static_assert(base::kMaxJoints == 3, "per_joint() is a Vec3");
  std::array<double, base::kMaxJoints> values_{};
};

struct DeviceConfig {
  std::string driver = "sim";    // a registered driver's name
  JointValues mass = 0.1;        // m (kg, or kg m^2 for a rotary joint), > 0
  JointValues damping = 2.0;     // b (N s/m, N m s/rad), > 0: the joints' own physical damping
  JointValues max_force = 10.0;  // |u| saturation of each joint (N or N m), > 0
  // device.kinematics: the mechanism the joints drive (one joint, today's axis, by default).
  kinematics::Kinematics kinematics;
  SimDeviceConfig sim;  // the simulated plant: the sim driver, and every loopback peer
  // device.<driver>; null for a driver without a section of its own (sim).
  std::shared_ptr<const DriverSettings> settings;
};

struct CouplingConfig {
  bool present = false;
  Coefficients numerator;    // C(z) numerator, powers of z^-1
  Coefficients denominator;  // C(z) denominator, powers of z^-1, leading coefficient != 0
};

struct WallConfig {
  double position = 0.0;      // x0 (m)
  int normal = 1;             // +1: wall occupies x > x0; -1: x < x0
  double stiffness = 1000.0;  // K (N/m), >= 0
  double damping = 0.0;       // B (N s/m), >= 0
  Discretization discretization = Discretization::kBackward;
  int delay_samples = 0;  // computation delay d beyond the driver's own, 0..kMaxDelaySamples
  bool no_pull = false;   // clamp f >= 0 (outside the theorems)
  CouplingConfig coupling;
};

// walls: at most this many (a box is six); the RT thread's per-wall arrays are this long.
inline constexpr std::size_t kMaxWalls = 8;

// One of `walls`: a half-space in task space (docs/kinematics.md, walls in task space), the
// task coordinates where a point p satisfies n . (x - p) > 0. Its law acts along n.
// What an entry of `walls` is: a half-space (a wall) or a spring-damper to a point (an
// attractor: bilateral, pulling towards its point along every task axis).
enum class WallKind { kWall, kAttractor };

struct TaskWallConfig {
  WallKind kind = WallKind::kWall;
  kinematics::Vec3 point = kinematics::Vec3::Zero();   // on the face (m), first m entries
  kinematics::Vec3 normal = kinematics::Vec3::Zero();  // unit (normalised as read), into the wall;
                                                       // zero for an attractor
  // stiffness, damping, discretization, delay_samples, no_pull, coupling along n; its
  // position and normal are the one-joint law's 0 and +1 on the coordinate n . (x - p). An
  // attractor runs it along each task axis e_k, on e_k . (x - p), with the contact never open.
  WallConfig law;
  // An attractor's largest force (N, the norm of its task force); +inf: the joints' limits alone.
  double max_force = std::numeric_limits<double>::infinity();
};

// safety.direction_check: before the wall is armed, a small force pulse and the sign of the
// motion it causes (docs/devices.md, the direction check; docs/math.md, its fit).
enum class DirectionCheckMode { kEnforce, kOff };
// What a device that does not move under the pulse (held firmly, too heavy for it, or never
// at rest long enough to try) gets: refused, or its wall armed unchecked, loudly.
enum class NoMotionAction { kRefuse, kRun };
struct DirectionCheckConfig {
  DirectionCheckMode mode = DirectionCheckMode::kEnforce;
  double level = 0.05;        // the pulse's force as a fraction of device.max_force, (0, 0.5]
  double duration_ms = 25.0;  // each half of the pulse (push, then brake), at least 3 ticks
  // The least motion, as a fraction of what the configured mass and damping would move free
  // under the pulse, that counts as motion; in (0, 1].
  double min_motion = 0.2;
  NoMotionAction on_no_motion = NoMotionAction::kRefuse;
  double rest_timeout_ms = 1000.0;  // how long the check waits for the device to be at rest
  // How much later than the driver declares the device's response may come (a USB link's
  // queue, a drive's own cycle): the fit searches delays up to this much more.
  double max_latency_ms = 50.0;
  friend bool operator==(const DirectionCheckConfig&, const DirectionCheckConfig&) = default;
};

enum class ClientWalls { kRemove, kKeep };

struct SafetyConfig {
  GateMode gate = GateMode::kEnforce;
  double operator_passivity_shortage = 0.0;  // eta (N s/m), >= 0
  double passivity_margin = 0.1;             // pass needs b_req <= (1 - margin) b; in [0, 1)
  double max_speed = 10.0;  // |dx/dt| between samples above this is an encoder fault (m/s)
  // How fast a wall a reload or a scene request moved slides to its new place (m/s).
  double max_wall_speed = 0.25;
  // What the walls a client added do when its connection to the control socket ends
  // (docs/clients.md): removed at the next tick boundary, or kept (then the configuration's).
  ClientWalls client_walls_on_leave = ClientWalls::kRemove;
  // A force a client commands directly (servo_cf, docs/clients.md): saturated to this norm (N;
  // 0: no client may command a force); held this long after it arrives, then ramped to zero
  // over client_force_ramp_ms; and off while it has put more than client_force_energy_j into
  // the device (its observer refills that much a second).
  double client_force_limit = 0.0;
  double client_force_hold_ms = 100.0;
  double client_force_ramp_ms = 50.0;
  double client_force_energy_j = 1.0;
  int stale_fault_ticks = 3;  // consecutive reads with no new position that fault the loop
  // A gap of this many samples or more in the device's own sequence counter faults the loop
  // (the loop ran on data older than it knew); 0: gaps are counted and logged only.
  std::uint32_t sequence_gap_fault = 1;
  PassivityControl passivity_controller = PassivityControl::kObserve;
  // The most damping (N s/m) the passivity controller adds; > 0.
  double passivity_max_damping = 20.0;
  DirectionCheckConfig direction_check;
  // The runaway guard: a penetration beyond this while the wall pushes at device.max_force
  // faults (the wall is not holding). 0: kRunawayMargin * max_force / wall.stiffness.
  double max_penetration = 0.0;
};

// The runaway guard's default bound, as a multiple of the penetration at which the wall's
// force reaches device.max_force (max_force / K): the saturated wall no longer holds beyond it.
inline constexpr double kRunawayMargin = 1.5;

struct AnalysisConfig {
  double operator_stiffness = 500.0;  // k_h of the operator model for the oscillation check
  double operator_damping = 5.0;      // b_h of that model
  Coefficients transparency_weight_numerator{1.0};  // W(z), powers of z^-1
  Coefficients transparency_weight_denominator{1.0};
};

// telemetry.max_segment_mb / max_total_mb: at most this many MB (2^20 bytes).
inline constexpr long long kMaxLogMegabytes = 1LL << 24;  // 16 TB: a bound, not advice

struct TelemetryConfig {
  std::string log_path;                 // empty: no tick log unless --log is given
  std::uint32_t ring_capacity = 65536;  // records between RT thread and writer, 64..2^22
  // A log rolls to a new segment (each a complete log) before it would pass this; 0: never.
  std::uint32_t max_segment_mb = 64;
  // The oldest segments and older runs' logs at the same path are deleted to keep them all
  // under this; 0: nothing is deleted. Needs max_segment_mb, and at least twice it.
  std::uint32_t max_total_mb = 1024;
};

struct Config {
  std::string source_name;     // file name shown in messages ("config/sim.yaml")
  std::string effective_yaml;  // the configuration after --set, as recorded in tick logs
  // Where each key present in the document came from, by key path: "sim.yaml:12" or
  // "--set wall.damping=1e306". Lets checks made after loading (derived quantities, the
  // drivers) name the place a person must edit.
  std::map<std::string, std::string, std::less<>> key_locations;
  LoopConfig loop;
  DeviceConfig device;
  WallConfig wall;  // the wall of a device of one joint
  // The walls of a device with several task axes (device.kinematics); none by default.
  std::vector<TaskWallConfig> walls;
  SafetyConfig safety;
  AnalysisConfig analysis;
  TelemetryConfig telemetry;

  // The location of `key_path`, or of the nearest enclosing key the document has, or
  // source_name when the value is a default: the prefix of a "WHERE: key: what" message.
  std::string locate(std::string_view key_path) const;
};

}  // namespace hapticd::config
