// One `hapticd run`: start-up (device configured, gate, log, loop), the servo (enable, RT
// thread, supervision of signals, the watchdog and the control socket), and the end (zero,
// disable, close, summary). With `--on-fault hold` a fault does not end the run: the device
// stays latched with output off and the daemon waits for `clear-fault`, which re-arms only
// through the same gate and only with the device outside the wall. It answers the control
// socket (status, stop, reload, clear-fault) on the socket's thread; a reload is parsed,
// checked and gated off the RT thread and swapped in at a tick boundary (loop/law_swap.h).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "control/controller.h"
#include "loop/law_swap.h"
#include "loop/rt_setup.h"
#include "loop/servo_loop.h"
#include "loop/wall_moves.h"
#include "service/control/control_server.h"
#include "service/run/device_session.h"
#include "service/run/run_command.h"
#include "service/run/run_summary.h"
#include "service/run/run_support.h"
#include "service/run/run_threads.h"
#include "service/run/state_stream.h"
#include "service/stop_signals.h"
#include "telemetry/state_block.h"

namespace hapticd::service {

class RunSession final : public ControlHandler {
 public:
  RunSession(const RunOptions& options, config::Config cfg, SignalWatch& signals);
  ~RunSession() override;

  // The whole run; returns the exit code (docs/operations.md).
  int run();

  // Control socket thread: status, stop, reload, clear-fault, scene, state.
  nlohmann::json handle(const Request& request) override;
  // The state block's descriptor, passed with the answer to "state".
  int descriptor(const Request& request) override;

 private:
  enum class Phase { kStarting, kRunning, kHeld, kEnded };
  static const char* name(Phase p);

  bool start_up(gate::GateReport& report);
  loop::LoopResult arm();
  void supervise(RtThread& rt);
  bool hold();
  std::string try_clear();
  void on_signal(int sig, RtThread* rt);
  void accumulate(const loop::LoopResult& r);
  int finish();

  // A reload's new configuration, its gate report and the law built from it (the walls, for
  // a device of several joints).
  struct Prepared {
    config::Config cfg;
    gate::GateReport report;
    std::unique_ptr<control::Controller> law;
    std::unique_ptr<loop::SceneWalls> walls;
    std::vector<Derating> derated;  // what safety.gate: derate lowered
  };

  nlohmann::json status() const;
  nlohmann::json reload(const std::string& text, const std::string& source,
                        const std::vector<std::string>& sets);
  // A client's change to the walls (scene_edit.h), applied as a reload of the running
  // configuration with its walls edited.
  nlohmann::json scene(const SceneEdit& edit, std::uint64_t client);
  // A client's move of one wall (scene_edit.h): no new gate, when the gate proved the walls
  // movable; handed to the loop through moves_ and answered once a tick has taken it.
  nlohmann::json move(const SceneEdit& edit);
  // reload() and scene() under reload_mutex_: `what` names it in messages ("reload", "scene
  // add"), `continues` (null: wall i goes on from wall i) says which running wall each new
  // one goes on from.
  // `owner`: the client a new wall belongs to (0: none; docs/clients.md, a client leaving).
  nlohmann::json apply(const std::string& text, const std::string& source,
                       const std::vector<std::string>& sets, const std::string& what,
                       const std::vector<int>* continues, std::uint64_t owner = 0);
  nlohmann::json commit(Prepared& next, Phase phase, const std::string& source,
                        const std::string& what, const std::vector<int>* continues,
                        std::uint64_t owner);
  // A client left (ControlHandler): the walls it added go at the next tick boundary (or stay,
  // safety.client_walls_on_leave), with no new gate: fewer walls only ask less of the device.
  void left(std::uint64_t client) override;
  // A client's commanded force (loop/client_force.h): checked, saturated, handed to the loop.
  nlohmann::json servo_cf(const Request& request);
  bool holds(std::uint64_t client) const override;
  // The decimated state stream (state_stream.h), on the control socket's thread.
  bool push(std::uint64_t client, std::size_t pending, std::string& out) override;
  int push_wait_ms() const override;
  // The walls at `gone` removed through commit(), judged by the verdicts the running walls had.
  void remove_walls(const std::vector<std::size_t>& gone, const std::string& why);
  Prepared prepare(const config::Config& running, const std::string& text,
                   const std::string& source, const std::vector<std::string>& sets,
                   const std::vector<int>* continues) const;
  std::optional<std::uint64_t> swap_in(Prepared& next, const std::string& source);
  // Offers `next` on `swap` and waits for the tick that takes it (none: the loop ended first);
  // throws ControlRefusal when the loop reached no tick boundary in time.
  template <class T>
  std::optional<std::uint64_t> offer(loop::TickSwap<T>& swap, T* next, const std::string& source);
  config::Config config_snapshot() const;
  nlohmann::json reload_file();
  nlohmann::json clear_fault();
  void set_phase(Phase p);

  const RunOptions& options_;
  SignalWatch& signals_;
  const bool realtime_;
  RunSummary summary_;
  // What safety.gate: derate last did, for `status` (guarded by mutex_).
  std::vector<Derating> derated_;
  std::optional<DeviceSession> session_;
  TickLog log_;
  loop::RtStatus rt_;
  std::optional<loop::CpuDmaLatencyRequest> pm_qos_;
  loop::LawSwap swap_;
  loop::SceneSwap scene_swap_;                       // several joints: new walls
  loop::WallMoves moves_;                            // several joints: a client's wall moves
  std::unique_ptr<loop::ClientForce> client_force_;  // several joints: a client's force
  std::unique_ptr<control::Controller> active_;      // the law the loop runs
  SceneParts scene_;  // a device of several joints: the walls the loop steps instead
  // Walls a reload accepted while no loop ran (a held fault): the next arming takes them.
  std::unique_ptr<loop::SceneWalls> pending_walls_;
  // The clients' state block (with a control socket): made before the socket, gone after it.
  std::unique_ptr<telemetry::StateBlock> state_;
  std::unique_ptr<StateStream> stream_;  // read from state_; the control socket's thread alone
  std::unique_ptr<loop::ServoLoop> servo_;
  std::unique_ptr<ControlServer> server_;
  int wake_fd_ = -1;  // eventfd: the control thread wakes the supervisor (stop, clear-fault)
  bool reload_pending_ = false;  // a SIGHUP taken before the servo ran (supervisor thread)

  mutable std::mutex mutex_;           // guards what the control thread reads or asks for, below
  config::Config cfg_;                 // replaced by an accepted reload
  nlohmann::json gate_;                // the verdict on cfg_, as JSON
  gate::GateReport report_;            // the verdict on cfg_
  std::vector<std::uint64_t> owners_;  // each of cfg_.walls' client (0: the configuration's)
  std::uint64_t force_owner_ = 0;      // the client whose force client_force_ renders (0: none)
  std::uint64_t reloads_ = 0;          // accepted reloads: cfg_ and the law swapped in agree
  Phase phase_ = Phase::kStarting;
  std::string fault_;  // the last fault, described
  bool stop_asked_ = false;
  bool clear_asked_ = false;
  std::optional<std::string> clear_result_;  // "" cleared, else why not
  std::condition_variable cleared_;

  std::mutex reload_mutex_;  // one reload at a time (socket, SIGHUP)
};

}  // namespace hapticd::service
