#include "verify/workspace_verify.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>

#include "analysis/normal_passivity.h"
#include "analysis/passivity.h"
#include "analysis/wall_model.h"
#include "control/control_law.h"
#include "control/scene.h"
#include "kinematics/kinematics.h"
#include "loop/servo_loop.h"
#include "verify/frequency_sweep.h"

namespace hapticd::verify {
namespace {

using kinematics::Vec3;

// 0.01 mm. The torque is held in joint space over a period, not the force in task space, so the
// torques' work differs from the wall's own by a term first order in the motion's size (the
// Jacobian's change over it): 5e-3 of b_req at 0.1 mm at the Falcon box's corner, 5e-4 here,
// against the tolerance of 1e-3. Far above the forward kinematics' tolerance (1e-10 rad).
constexpr double kAmplitude = 1e-5;

// A device whose joints follow the operator's imposed motion, one precomputed position a read,
// and which keeps every torque written.
class ImposedJoints final : public Device {
 public:
  ImposedJoints(const std::vector<Vec3>& path, int joints) : path_(path), joints_(joints) {
    torques_.reserve(path.size());
    configure();
    enable();
  }
  std::string_view driver_name() const noexcept override { return "imposed"; }
  const std::vector<Vec3>& torques() const { return torques_; }

 protected:
  DeviceInfo on_configure() override {
    return {"imposed motion", 0, 0, static_cast<std::size_t>(joints_)};
  }
  void on_enable() override {}
  void on_disable() noexcept override {}
  void on_close() noexcept override {}
  IoStatus on_read(std::span<PositionSample> samples) noexcept override {
    const Vec3& q = path_[std::min(next_++, path_.size() - 1)];
    for (std::size_t j = 0; j < samples.size(); ++j) samples[j].position = q[static_cast<int>(j)];
    return IoStatus::kOk;
  }
  IoStatus on_write(std::span<const double> forces) noexcept override {
    Vec3 tau = Vec3::Zero();
    for (std::size_t j = 0; j < forces.size(); ++j) tau[static_cast<int>(j)] = forces[j];
    if (torques_.size() < torques_.capacity()) torques_.push_back(tau);
    return IoStatus::kOk;
  }
  std::string describe(const DeviceFault&) const override { return "imposed motion"; }

 private:
  const std::vector<Vec3>& path_;
  int joints_;
  std::size_t next_ = 0;
  std::vector<Vec3> torques_;
};

// One wall at x*: the configuration measured (the wall alone, its delay the driver's too, the
// workspace a millimetre wider so the motion around x* on its edge stays a pose), the motion's
// direction d and the joints' damping.
struct Measured {
  config::Config cfg;
  control::ControlLaw law;
  Vec3 point = Vec3::Zero();  // the wall placed so that x* is 2A inside it
  Vec3 normal = Vec3::Zero();
  Vec3 x_star = Vec3::Zero();
  Vec3 d = Vec3::Zero();
  Vec3 joint_damping = Vec3::Zero();
  double normal_damping = 0.0;  // b_n at x*, the gate's formula
  int n = 0;
};

class NormalSweep final : public FrequencySweep {
 public:
  NormalSweep(const Measured& m, int total_delay, double slowest_pole, bool tustin)
      : FrequencySweep(m.cfg.loop.sample_period_s(), tustin),
        m_(m),
        warmup_(warmup_ticks(total_delay, slowest_pole)) {}
  double normal_damping() const { return normal_damping_; }

 private:
  double measure(double theta, std::int64_t period, std::int64_t window) override {
    const double t = m_.cfg.loop.sample_period_s();
    const std::int64_t warm = (warmup_ + period - 1) / period * period;
    const std::int64_t ticks = warm + window + 1;
    std::vector<Vec3> x, q;
    for (std::int64_t k = 0; k < ticks; ++k) {
      x.push_back(m_.x_star + m_.d * kAmplitude * std::cos(theta * static_cast<double>(k)));
      const kinematics::JointSolution s = kinematics::inverse(m_.cfg.device.kinematics, x.back());
      if (s.status != kinematics::Status::kOk) {
        throw std::runtime_error(std::string("verify: the imposed motion left the mechanism: ") +
                                 kinematics::status_name(s.status));
      }
      q.push_back(s.q);
    }
    ImposedJoints device(q, m_.n);
    control::ObserverParams off;
    off.mode = config::PassivityControl::kOff;
    off.sample_period = t;
    loop::SceneWalls walls(
        std::make_unique<control::Scene>(std::vector<control::WallGeometry>{{m_.point, m_.normal}},
                                         std::vector<control::ControlLaw>{m_.law}),
        {off});
    loop::SceneState state(m_.cfg.device.kinematics, walls,
                           Vec3::Constant(std::numeric_limits<double>::max()));
    loop::LoopOptions lo;
    lo.sample.realtime = false;
    lo.sample.period_ns = m_.cfg.loop.period_ns();
    lo.sample.max_speed = std::numeric_limits<double>::infinity();
    lo.max_ticks = static_cast<std::uint64_t>(ticks);
    lo.scene = &state;
    control::Controller unused(m_.law);
    loop::ServoLoop loop(device, unused, nullptr, lo);
    const std::atomic<bool> stop{false};
    const loop::LoopResult r = loop.run(stop);
    if (r.fault.cause != loop::FaultCause::kNone) {
      throw std::runtime_error("verify: the measurement loop faulted: " + loop::describe(r.fault));
    }
    if (r.count(loop::kCounterContactTicks) != r.ticks) {
      throw std::runtime_error(
          "verify: the measurement loop left contact, so the loop measured "
          "was not the linear one the bound is about");
    }
    ticks_ += static_cast<std::uint64_t>(ticks);
    // Over the window: the torques' work, the normal motion and what the joints dissipated.
    double work = 0.0, motion = 0.0, dissipated = 0.0;
    for (std::int64_t k = warm; k < warm + window; ++k) {
      const auto i = static_cast<std::size_t>(k);
      const Vec3 dq = q[i + 1] - q[i];
      const double ds = m_.normal.dot(x[i + 1] - x[i]);
      work += device.torques()[i].dot(dq);
      motion += ds * ds / t;
      dissipated += dq.cwiseProduct(dq).dot(m_.joint_damping) / t;
    }
    normal_damping_ = dissipated / motion;
    return work / motion;
  }

  const Measured& m_;
  std::int64_t warmup_;
  double normal_damping_ = 0.0;
};

// An attractor's law along any unit direction u is its one-axis law on u . (x - p) (the same
// filter on every axis, linear): measured as a wall whose normal is the direction in which the
// device at x has the least damping, lambda_min(B_c)'s eigenvector, where the gate judged it.
config::TaskWallConfig as_wall(const config::Config& cfg, const config::TaskWallConfig& w,
                               const Vec3& x) {
  if (w.kind != config::WallKind::kAttractor) return w;
  const kinematics::JointSolution s = kinematics::inverse(cfg.device.kinematics, x);
  const kinematics::Pose pose = kinematics::forward(cfg.device.kinematics, s.q, x);
  analysis::DeviceDamping dd;
  dd.jacobian = pose.J;
  dd.m = pose.m;
  dd.n = pose.n;
  dd.joint_damping = cfg.device.damping.per_joint();
  analysis::Mat3 b_c;
  if (s.status != kinematics::Status::kOk || pose.status != kinematics::Status::kOk ||
      !analysis::task_damping(dd, b_c)) {
    throw std::invalid_argument("verify: the attractor's worst configuration has no B_c");
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(b_c.topLeftCorner(dd.m, dd.m));
  config::TaskWallConfig one = w;
  one.kind = config::WallKind::kWall;
  one.normal = Vec3::Zero();
  one.normal.head(dd.m) = eig.eigenvectors().col(0).normalized();  // the least eigenvalue's
  return one;
}

Measured measured_wall(const config::Config& cfg, const config::TaskWallConfig& w, int total_delay,
                       const Vec3& x_star) {
  Measured m;
  m.cfg = cfg;
  m.cfg.safety.max_penetration = 0.0;
  kinematics::Box& box = kinematics::workspace(m.cfg.device.kinematics);
  box.lower.array() -= 1e-3;
  box.upper.array() += 1e-3;
  config::TaskWallConfig one = w;
  one.law.no_pull = false;
  one.law.delay_samples = total_delay;
  m.law = control::task_wall_law(m.cfg, one);
  m.law.require_outside_start = false;  // the motion starts in contact, where it stays
  m.law.linear_contact = true;          // the loop of the bound: linear, never leaving contact
  m.normal = w.normal;
  m.x_star = x_star;
  m.point = x_star - 2.0 * kAmplitude * w.normal;
  m.n = kinematics::joint_count(cfg.device.kinematics);
  const kinematics::JointSolution s = kinematics::inverse(cfg.device.kinematics, x_star);
  const kinematics::Pose pose = kinematics::forward(cfg.device.kinematics, s.q, x_star);
  if (s.status != kinematics::Status::kOk || pose.status != kinematics::Status::kOk) {
    throw std::invalid_argument("verify: the worst configuration is not a pose of the mechanism");
  }
  analysis::DeviceDamping dd;
  dd.jacobian = pose.J;
  dd.m = pose.m;
  dd.n = pose.n;
  dd.joint_damping = cfg.device.damping.per_joint();
  m.joint_damping = dd.joint_damping;
  const double b_n = analysis::normal_damping(dd, w.normal);
  if (!(b_n > 0.0) || !std::isfinite(b_n)) {
    throw std::invalid_argument("verify: the device cannot move along the wall's normal there");
  }
  // The least dissipating motion with n . d = 1: joints b_n B_j^-1 J^T n, the task J times it.
  const Vec3 jtn = pose.J.transpose() * w.normal;
  Vec3 joint_motion = Vec3::Zero();
  for (int j = 0; j < m.n; ++j) joint_motion[j] = b_n * jtn[j] / dd.joint_damping[j];
  m.d = pose.J * joint_motion;
  m.normal_damping = b_n;
  return m;
}

WallVerify verify_wall(const config::Config& cfg, const config::TaskWallConfig& w, int device_delay,
                       const Vec3& x_star) {
  WallVerify v;
  v.position = x_star;
  const int total = w.law.delay_samples + device_delay;
  const Measured m = measured_wall(cfg, as_wall(cfg, w, x_star), total, x_star);
  config::Config one = cfg;
  one.wall = w.law;
  const analysis::TransferFunction e =
      analysis::environment_filter(control::wall_params(one, w.law.stiffness));
  const analysis::TransferFunction h = analysis::contact_map(e, control::coupling_filter(one));
  const analysis::PassivityBound pb =
      analysis::passivity_bound(h, cfg.loop.sample_period_s(), total, 0.0);
  if (!std::isfinite(pb.required_damping)) {
    throw std::invalid_argument("verify: a wall's passivity bound is infinite (" + pb.note + ")");
  }
  v.analytic_required_damping = pb.required_damping;
  const bool tustin = w.law.discretization == config::Discretization::kTustin;
  NormalSweep sweep(m, total, analysis::spectral_radius(h), tustin);
  v.measured_required_damping = worst_damping(sweep, tustin);
  v.sweep = sweep.points();
  v.worst_frequency_hz = worst_frequency_hz(v.sweep, v.measured_required_damping);
  v.ticks = sweep.ticks();
  v.measured_normal_damping = sweep.normal_damping();
  v.normal_damping = m.normal_damping;
  const double scale = std::max(std::abs(v.analytic_required_damping), 1e-12);
  v.relative_error = std::abs(v.measured_required_damping - v.analytic_required_damping) / scale;
  v.agrees = v.relative_error <= kVerifyTolerance;
  v.measured_passive = v.measured_required_damping <= v.measured_normal_damping;
  return v;
}

}  // namespace

WorkspaceVerifyResult verify_workspace(const config::Config& cfg, int device_delay_samples,
                                       std::span<const Vec3> worst) {
  if (worst.size() != cfg.walls.size()) {
    throw std::invalid_argument("verify: one worst configuration per wall");
  }
  WorkspaceVerifyResult r;
  r.amplitude = kAmplitude;
  r.device_delay_samples = device_delay_samples;
  r.agrees = true;
  for (std::size_t i = 0; i < cfg.walls.size(); ++i) {
    r.walls.push_back(verify_wall(cfg, cfg.walls[i], device_delay_samples, worst[i]));
    r.agrees = r.agrees && r.walls.back().agrees;
  }
  return r;
}

}  // namespace hapticd::verify
