// hapticd's C++ client (docs/clients.md): a connection to a running daemon's control socket
// (one JSON object per line each way, docs/operations.md) and what an application asks through
// it: the state, the scene's walls. Blocking, with a time-out on every answer; one connection
// per thread. Installed with the daemon (`pkg-config --cflags --libs hapticd-client`); hapticctl
// is built on it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "state_reader.h"

namespace hapticd::client {

// The control protocol's version this client speaks ("v" of every request and answer).
inline constexpr int kProtocolVersion = 1;

// The socket could not be reached, or gave no well-formed answer: what() names the socket and
// what went wrong ("/run/hapticd/x.sock: cannot connect: No such file or directory").
class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The daemon answered "ok": false: what() is its reason, code() the exit code it stands for
// (2 a malformed request or invalid configuration, 3 the gate refused it, 1 anything else).
class Refused : public std::runtime_error {
 public:
  Refused(const std::string& why, int code) : std::runtime_error(why), code_(code) {}
  int code() const noexcept { return code_; }

 private:
  int code_;
};

// The socket of instance `name` of the template unit hapticd@.service:
// /run/hapticd/NAME/control.sock.
std::string instance_socket(const std::string& name);

// One request on a connection of its own: connects to `socket`, sends `request` (its "v" set)
// and returns the answer parsed, "ok" true or false. Throws ClientError when it cannot
// connect, the daemon hangs up without an answer, the answer is not a protocol object, or none
// arrives within `timeout_ms`.
nlohmann::json request(const std::string& socket, nlohmann::json request, int timeout_ms);

// When a move took effect: the first tick that rendered it and CLOCK_MONOTONIC then (both
// none while the daemon's output is off: the next arming takes it).
struct Applied {
  std::optional<std::uint64_t> tick;
  std::optional<std::int64_t> time_ns;
};

class Connection {
 public:
  // Connects; throws ClientError.
  explicit Connection(const std::string& socket, int timeout_ms = 30000);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Sends `request` (its "v" set) and returns the answer, "ok" true or false. ClientError as
  // request() above; after one the connection is closed (a late answer must not be taken for
  // the next request's), and every later call throws.
  nlohmann::json request(nlohmann::json request);
  // request(), throwing Refused for "ok": false.
  nlohmann::json call(nlohmann::json request);

  nlohmann::json status();  // the "status" member
  // The state block: the daemon's descriptor, mapped (state_reader.h).
  StateReader state();
  // Scene requests: the answer's "scene" member. add_wall returns the new wall's index; the wall
  // goes when this connection closes unless `keep` (none: as the daemon's
  // safety.client_walls_on_leave says).
  std::size_t add_wall(const nlohmann::json& wall, std::optional<bool> keep = std::nullopt);
  // An attractor (a spring-damper pulling to `point` along every task axis, gated like a wall):
  // add_wall of {"kind": "attractor", point, stiffness, damping, max_force (N; none: the joints'
  // limits alone)}; its index among the walls.
  std::size_t add_attractor(std::span<const double> point, double stiffness, double damping,
                            std::optional<double> max_force = std::nullopt,
                            std::optional<bool> keep = std::nullopt);
  nlohmann::json change_wall(std::size_t index, const nlohmann::json& keys);
  nlohmann::json remove_wall(std::size_t index);
  // Moves walls[index] to `point`: one number per task axis of the device (StateReader::axes).
  Applied move_wall(std::size_t index, std::span<const double> point);
  // Commands a force (N, one number per task axis; CRTK's servo_cf), added to the walls'. Send
  // it again within the daemon's safety.client_force_hold_ms or it fades to zero; it goes at
  // once when this connection closes. The answer's "servo_cf": the force taken (saturated to
  // safety.client_force_limit) and whether it was saturated.
  nlohmann::json servo_cf(std::span<const double> force);
  // The state stream: every `every`-th tick's state as a line of its own on this connection
  // (0 stops it); the answer's "stream" member (every, rate_hz, first_sample). For a reader
  // that wants the state over the socket rather than the state block.
  nlohmann::json stream(std::uint32_t every);
  // The next sample of the stream (the line's "stream" member: tick, time_ns, measured_js,
  // measured_cp, measured_cv, setpoint_cf, ..., missed), waiting up to `timeout_ms`; none when
  // none came. Samples that arrive while a request waits for its answer are kept for this.
  std::optional<nlohmann::json> next_sample(int timeout_ms);

 private:
  std::string line();  // the next line, receiving any descriptor passed with it
  std::optional<std::string> line_within(int timeout_ms);  // none: none within timeout_ms
  // The next line that is not a stream sample (those go to samples_).
  std::string answer_line();

  std::string socket_;
  int timeout_ms_;
  int fd_ = -1;
  std::string in_;
  int passed_fd_ = -1;                  // the descriptor the last answer carried, until taken
  std::deque<nlohmann::json> samples_;  // stream samples not yet taken
};

}  // namespace hapticd::client
