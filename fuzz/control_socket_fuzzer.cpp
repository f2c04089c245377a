// libFuzzer target for the control socket (service/control_server.h, control_protocol.h): the
// input is what one client writes to a running ControlServer before it half-closes, as a
// hostile or broken client would: any bytes, many lines, partial lines, invalid UTF-8. The
// handler answers as the daemon does for the parts that do not need a running loop: status, stop,
// clear-fault refused, reload through the real configuration loader and the real check of
// what a reload may change (reload_blockers) against the embedded default, and scene requests
// through the real edit of a gantry's walls (edit_walls) and the loader.
// Invariants: the server never crashes or hangs; every complete line gets exactly one answer,
// in order, and a line with no newline at the end of input gets none; every answer is one line
// of JSON with "v": 1, "ok" true or false, and when false a non-empty "error" and a code of
// docs/operations.md (1, 2 or 3); a request that is a JSON object gets its "id" back unchanged.
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "config/config_loader.h"
#include "service/control/control_server.h"
#include "service/run/reload_check.h"
#include "service/run/scene_edit.h"
#include "support/check.h"

namespace {

namespace service = hapticd::service;
namespace config = hapticd::config;
using hapticd::fuzz::require;
using nlohmann::json;

class DaemonLikeHandler : public service::ControlHandler {
 public:
  json handle(const service::Request& r) override {
    switch (r.command) {
      case service::Command::kStatus:
        return {{"status", {{"state", "running"}, {"tick", 42}, {"config", "fuzz \xC3\xA9"}}}};
      case service::Command::kStop:
        return {{"stopping", true}};
      case service::Command::kClearFault:
        throw service::ControlRefusal("no fault to clear", 1);
      case service::Command::kReload:
        return reload(r);
      case service::Command::kScene:
        return scene(r);
      case service::Command::kState:
        return {{"state", {{"layout", 1}}}};
      case service::Command::kServoCf:  // what the parser promises a force
        require(r.force_axes >= 1 && r.force_axes <= 3, "a force has 1 to 3 numbers");
        for (const double v : r.force) require(std::isfinite(v), "a force is finite");
        return {{"servo_cf", {{"saturated", false}}}};
      case service::Command::kStream:  // what the parser promises a stream
        require(r.every <= service::kMaxStreamEvery, "a stream's every is in range");
        streams_[r.client] = r.every > 0 ? kLinesPerStream : 0;
        return {{"stream", {{"every", r.every}}}};
    }
    throw service::ControlRefusal("unknown command");
  }

  static constexpr std::string_view kStreamLine = "{\"v\":1,\"stream\":{\"tick\":7}}\n";
  // A streaming client gets a few unasked lines between its answers, as the daemon's state
  // stream sends them: they must never split or reorder an answer.
  bool push(std::uint64_t client, std::size_t /*pending*/, std::string& out) override {
    int& left = streams_[client];
    if (left <= 0) return false;
    --left;
    out += kStreamLine;
    return true;
  }
  int push_wait_ms() const override { return 1; }
  void left(std::uint64_t client) override { streams_.erase(client); }

 private:
  json reload(const service::Request& r) {
    config::Config next;
    try {
      next = config::load_config_text(r.config_text, r.source);
    } catch (const config::ConfigError& e) {
      throw service::ControlRefusal(std::string("reload refused: ") + e.what(), 2);
    }
    const auto blockers = service::reload_blockers(running_, next);
    if (!blockers.empty()) throw service::ControlRefusal("reload refused: " + blockers[0], 2);
    return {{"reload", {{"accepted", true}}}};
  }

  // A scene request through the real edit of the document (scene_edit.h) and the real
  // loader, on a gantry of two walls.
  json scene(const service::Request& r) {
    if (r.scene.op == service::SceneEdit::Op::kMove) {  // what the parser promises a move
      require(r.scene.axes >= 1 && r.scene.axes <= 3, "a move's point has 1 to 3 numbers");
      for (const double v : r.scene.point) require(std::isfinite(v), "a move's point is finite");
      return {{"scene", {{"op", "move"}, {"index", r.scene.index}}}};
    }
    const service::EditedScene e = service::edit_walls(kGantry, r.scene);  // ControlRefusal
    require(e.continues.size() == (r.scene.op == service::SceneEdit::Op::kAdd      ? 3u
                                   : r.scene.op == service::SceneEdit::Op::kRemove ? 1u
                                                                                   : 2u),
            "an edit adds, keeps or removes exactly one wall");
    try {
      config::load_config_text(e.yaml, "scene request");
    } catch (const config::ConfigError& error) {
      throw service::ControlRefusal(std::string("scene refused: ") + error.what(), 2);
    }
    return {{"scene", {{"accepted", true}, {"walls", e.continues.size()}}}};
  }

  static constexpr const char* kGantry =
      "device:\n  kinematics: {kind: cartesian, joints: 2, scale: [1, 1], sign: [1, 1]}\n"
      "walls:\n  - {point: [0.02, 0], normal: [1, 0], stiffness: 500}\n"
      "  - {point: [0, 0.02], normal: [0, 1], stiffness: 500}\n";
  config::Config running_ = config::load_embedded_default();
  static constexpr int kLinesPerStream = 3;
  std::map<std::uint64_t, int> streams_;  // the server's thread alone
};

struct Rig {
  DaemonLikeHandler handler;
  std::string path = "/tmp/hapticd-control-fuzz-" + std::to_string(getpid()) + ".sock";
  service::ControlServer server{path, handler};
};

Rig& rig() {
  // Lives until exit: the server's thread must outlive every input. Its socket file goes
  // with the process.
  static Rig* r = [] {
    Rig* made = new Rig;
    std::atexit([] { unlink(rig().path.c_str()); });
    return made;
  }();
  return *r;
}

int connect_to(const std::string& path) {
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  require(fd >= 0, "socket()");
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  require(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0, "connect()");
  return fd;
}

// Writes the input and reads the answers at the same time (a client that only writes would
// be dropped once its unread answers pile up, which is the server's right), until the server
// hangs up.
std::string exchange(int fd, const std::uint8_t* data, std::size_t size) {
  std::string answers;
  std::size_t sent = 0;
  bool shut = false;
  char buf[65536];
  for (;;) {
    if (!shut && sent == size) {
      shutdown(fd, SHUT_WR);
      shut = true;
    }
    pollfd p{fd, static_cast<short>(POLLIN | (shut ? 0 : POLLOUT)), 0};
    const int ready = poll(&p, 1, 10000);
    if (ready < 0 && errno == EINTR) continue;  // libFuzzer's timer signal
    require(ready == 1, "the server answers or hangs up within 10 s");
    if (p.revents & POLLOUT) {
      const ssize_t n = send(fd, data + sent, size - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
      require(n > 0, "send()");
      sent += static_cast<std::size_t>(n);
    }
    if (p.revents & (POLLIN | POLLHUP)) {
      const ssize_t n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
      if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
      require(n >= 0, "the server hangs up cleanly, never a reset", std::strerror(errno));
      if (n == 0) return answers;
      answers.append(buf, static_cast<std::size_t>(n));
    }
  }
}

void check_answer(std::string_view request, std::string_view answer) {
  const json a = json::parse(answer, nullptr, false);
  require(a.is_object(), "an answer is a JSON object", answer);
  require(a.value("v", 0) == service::kProtocolVersion, "an answer has \"v\": 1", answer);
  require(a.contains("ok") && a["ok"].is_boolean(), "an answer says ok true or false", answer);
  if (!a["ok"].get<bool>()) {
    require(a.contains("error") && a["error"].is_string() && !a["error"].get<std::string>().empty(),
            "a refusal says why", answer);
    const int code = a.value("code", 0);
    require(code == 1 || code == 2 || code == 3, "a refusal's code is 1, 2 or 3", answer);
  }
  const json q = json::parse(request, nullptr, false);
  if (q.is_object() && q.contains("id")) {
    require(a.contains("id") && a["id"] == q["id"], "the request's id comes back", answer);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // A request longer than the limit is refused and its client dropped (a test covers that);
  // here every line is answered.
  if (size > service::kMaxRequestBytes) return 0;
  const int fd = connect_to(rig().path);
  const std::string received = exchange(fd, data, size);
  close(fd);
  // The stream's lines come whole, between answers, never inside one: set aside, the rest
  // must be the answers alone.
  std::string answers;
  for (std::size_t at = 0, nl; (nl = received.find('\n', at)) != std::string::npos; at = nl + 1) {
    const std::string_view l = std::string_view(received).substr(at, nl - at + 1);
    if (l != DaemonLikeHandler::kStreamLine) answers += l;
  }
  if (const std::size_t tail = received.rfind('\n'); tail + 1 < received.size()) {
    answers += received.substr(tail == std::string::npos ? 0 : tail + 1);
  }

  const std::string_view in(reinterpret_cast<const char*>(data), size);
  std::size_t q = 0, a = 0;
  for (std::size_t nl; (nl = in.find('\n', q)) != std::string_view::npos; q = nl + 1) {
    const std::size_t end = answers.find('\n', a);
    require(end != std::string::npos, "every complete line is answered",
            std::to_string(q) + " bytes of requests answered in full");
    check_answer(in.substr(q, nl - q), std::string_view(answers).substr(a, end - a));
    a = end + 1;
  }
  require(a == answers.size(), "no answer without a request, none to a line left unfinished");
  return 0;
}
