#include "connection.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <utility>
#include <vector>

namespace hapticd::client {
namespace {

using nlohmann::json;

ClientError failure(const std::string& socket, const std::string& what, int err) {
  return ClientError(socket + ": " + what + ": " + std::strerror(err));
}

int connect_to(const std::string& socket) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (socket.size() >= sizeof addr.sun_path) throw failure(socket, "cannot connect", ENAMETOOLONG);
  std::memcpy(addr.sun_path, socket.c_str(), socket.size() + 1);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw failure(socket, "cannot create a socket", errno);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    close(fd);
    throw failure(socket, "cannot connect", err);
  }
  return fd;
}

// 0, or the errno that stopped the sending.
int send_all(int fd, const std::string& text) {
  for (std::size_t sent = 0; sent < text.size();) {
    const ssize_t n = send(fd, text.data() + sent, text.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? errno : EPIPE;
    sent += static_cast<std::size_t>(n);
  }
  return 0;
}

std::string request_line(json request) {
  request["v"] = kProtocolVersion;
  return request.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

json parsed(const std::string& socket, const std::string& line) {
  json answer = json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (answer.is_discarded() || !answer.is_object() || !answer.contains("ok")) {
    throw ClientError(socket +
                      ": the answer is not a control-protocol object: " + line.substr(0, 200));
  }
  return answer;
}

// recvmsg with room for one passed descriptor, which goes to `passed` (any earlier one closed).
ssize_t receive(int fd, char* buf, std::size_t size, int& passed) {
  iovec io{buf, size};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))];
  msghdr msg{};
  msg.msg_iov = &io;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = recvmsg(fd, &msg, MSG_CMSG_CLOEXEC);
  for (cmsghdr* c = n > 0 ? CMSG_FIRSTHDR(&msg) : nullptr; c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SCM_RIGHTS) continue;
    if (passed >= 0) close(passed);
    std::memcpy(&passed, CMSG_DATA(c), sizeof(int));
  }
  return n;
}

// A stream sample's line: {"v": 1, "stream": {...}}, never an answer (those carry "ok").
std::optional<json> sample_of(const std::string& line) {
  if (line.find("\"stream\"") == std::string::npos) return std::nullopt;
  json j = json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || j.contains("ok") || !j.contains("stream")) {
    return std::nullopt;
  }
  return std::move(j["stream"]);
}

}  // namespace

std::string instance_socket(const std::string& name) {
  return "/run/hapticd/" + name + "/control.sock";
}

json request(const std::string& socket, json request, int timeout_ms) {
  Connection c(socket, timeout_ms);
  return c.request(std::move(request));
}

Connection::Connection(const std::string& socket, int timeout_ms)
    : socket_(socket), timeout_ms_(timeout_ms), fd_(connect_to(socket)) {}

Connection::~Connection() {
  if (fd_ >= 0) close(fd_);
  if (passed_fd_ >= 0) close(passed_fd_);
}

json Connection::request(json request) {
  if (fd_ < 0) throw ClientError(socket_ + ": the connection was closed after an error");
  const std::string text = request_line(std::move(request));
  try {
    if (const int err = send_all(fd_, text); err != 0) {
      // A daemon that refuses this peer answers at once and hangs up, maybe before the request
      // was sent: its answer is still there to read.
      timeout_ms_ = std::min(timeout_ms_, 1000);
      try {
        return parsed(socket_, answer_line());
      } catch (const ClientError&) {
        throw failure(socket_, "cannot send the request", err);
      }
    }
    return parsed(socket_, answer_line());
  } catch (const ClientError&) {
    close(fd_);
    fd_ = -1;
    throw;
  }
}

json Connection::call(json request) {
  json answer = this->request(std::move(request));
  if (!answer["ok"].is_boolean() || !answer["ok"].get<bool>()) {
    const json& error = answer["error"];
    throw Refused(error.is_string() ? error.get<std::string>() : "refused without a reason",
                  answer.value("code", 1));
  }
  return answer;
}

std::string Connection::line() {
  if (std::optional<std::string> l = line_within(timeout_ms_)) return std::move(*l);
  throw ClientError(socket_ + ": no answer within " + std::to_string(timeout_ms_) + " ms");
}

std::optional<std::string> Connection::line_within(int timeout_ms) {
  using clock = std::chrono::steady_clock;
  const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
  char buf[65536];
  for (;;) {
    if (const auto nl = in_.find('\n'); nl != std::string::npos) {
      std::string l = in_.substr(0, nl);
      in_.erase(0, nl + 1);
      return l;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
    if (left <= 0) return std::nullopt;
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(left)) < 0 && errno != EINTR) {
      throw failure(socket_, "poll", errno);
    }
    if (p.revents == 0) continue;
    const ssize_t n = receive(fd_, buf, sizeof buf, passed_fd_);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw failure(socket_, "cannot read the answer", errno);
    if (n == 0) throw ClientError(socket_ + ": the daemon closed the connection without an answer");
    in_.append(buf, static_cast<std::size_t>(n));
  }
}

std::string Connection::answer_line() {
  for (;;) {
    std::string l = line();
    if (std::optional<json> sample = sample_of(l)) {
      samples_.push_back(std::move(*sample));
      continue;
    }
    return l;
  }
}

json Connection::stream(std::uint32_t every) {
  return call({{"cmd", "stream"}, {"every", every}})["stream"];
}

std::optional<json> Connection::next_sample(int timeout_ms) {
  if (samples_.empty()) {
    if (fd_ < 0) throw ClientError(socket_ + ": the connection was closed after an error");
    try {
      std::optional<std::string> l = line_within(timeout_ms);
      if (!l) return std::nullopt;
      std::optional<json> sample = sample_of(*l);
      if (!sample) {
        throw ClientError(socket_ + ": a line that answers no request: " + l->substr(0, 200));
      }
      return sample;
    } catch (const ClientError&) {
      close(fd_);
      fd_ = -1;
      throw;
    }
  }
  json s = std::move(samples_.front());
  samples_.pop_front();
  return s;
}

json Connection::status() { return call({{"cmd", "status"}})["status"]; }

StateReader Connection::state() {
  if (passed_fd_ >= 0) close(std::exchange(passed_fd_, -1));  // nothing stale stands for it
  call({{"cmd", "state"}});
  if (passed_fd_ < 0) {
    throw ClientError(socket_ + ": the state answer carried no descriptor (SCM_RIGHTS)");
  }
  return StateReader(std::exchange(passed_fd_, -1));
}

std::size_t Connection::add_wall(const json& wall, std::optional<bool> keep) {
  json request = {{"cmd", "scene"}, {"op", "add"}, {"wall", wall}};
  if (keep) request["keep"] = *keep;
  return call(std::move(request))["scene"]["index"].get<std::size_t>();
}

std::size_t Connection::add_attractor(std::span<const double> point, double stiffness,
                                      double damping, std::optional<double> max_force,
                                      std::optional<bool> keep) {
  json wall = {{"kind", "attractor"},
               {"point", json(std::vector<double>(point.begin(), point.end()))},
               {"stiffness", stiffness},
               {"damping", damping}};
  if (max_force) wall["max_force"] = *max_force;
  return add_wall(wall, keep);
}

json Connection::change_wall(std::size_t index, const json& keys) {
  return call({{"cmd", "scene"}, {"op", "change"}, {"index", index}, {"wall", keys}})["scene"];
}

json Connection::remove_wall(std::size_t index) {
  return call({{"cmd", "scene"}, {"op", "remove"}, {"index", index}})["scene"];
}

Applied Connection::move_wall(std::size_t index, std::span<const double> point) {
  json p = json::array();
  for (const double v : point) p.push_back(v);
  const json s = call({{"cmd", "scene"}, {"op", "move"}, {"index", index}, {"point", p}})["scene"];
  Applied out;
  if (s["applied_at_tick"].is_number()) out.tick = s["applied_at_tick"].get<std::uint64_t>();
  if (s["applied_at_ns"].is_number()) out.time_ns = s["applied_at_ns"].get<std::int64_t>();
  return out;
}

json Connection::servo_cf(std::span<const double> force) {
  json f = json::array();
  for (const double v : force) f.push_back(v);
  return call({{"cmd", "servo_cf"}, {"force", f}})["servo_cf"];
}

}  // namespace hapticd::client
