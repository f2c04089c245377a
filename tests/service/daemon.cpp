#include "daemon.h"

#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace hapticd::testing {

std::string hapticctl_binary() { return HAPTICCTL_BINARY; }

std::string pressing_config(double k, const std::string& loop, const std::string& wall) {
  return "loop:\n"
         "  overrun_fault_streak: 1000000000\n" +
         loop +
         "device:\n"
         "  sim:\n"
         "    initial_position: -0.001\n"
         "    operator:\n"
         "      kind: hand\n"
         "      stiffness: 300\n"
         "      damping: 5\n"
         // At rest where it starts until the direction check has armed the wall (about 0.13 s),
         // then pressing 10 mm into it.
         "      setpoint: {shape: step, initial: -0.001, final: 0.01, at: 0.3}\n"
         "wall:\n"
         "  stiffness: " +
         std::to_string(k) +
         "\n"
         "  damping: 0\n" +
         wall;
}

Daemon::Daemon(const std::vector<std::string>& args, const std::string& dir) {
  static int counter = 0;
  const std::string tag = std::to_string(counter++);
  const auto at = [&](const std::string& name) {
    return dir.empty() ? temp_path(name + tag) : dir + "/" + name + tag;
  };
  socket_ = at("ctl") + ".sock";
  log_ = at("ticks") + ".hlog";
  summary_ = at("summary") + ".json";
  std::vector<std::string> argv{hapticd_binary(), "run",
                                "--socket",       socket_,
                                "--log",          log_,
                                "--summary-json", summary_,
                                "--set",          "loop.overrun_fault_streak=1000000000"};
  argv.insert(argv.end(), args.begin(), args.end());
  process_ = std::make_unique<BackgroundProcess>(argv, std::vector<std::string>{notify_.env()});
  ready_ = notify_.wait_for("READY=1", 20000);
}

Daemon::~Daemon() {
  if (collected_) return;
  process_->signal(SIGTERM);
  process_->wait();
}

ProcessResult Daemon::ctl(const std::vector<std::string>& args) const {
  std::vector<std::string> argv{hapticctl_binary(), "--socket", socket_};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_process(argv);
}

nlohmann::json Daemon::status() const {
  const ProcessResult r = ctl({"--json", "status"});
  if (r.exit_code != 0) return nullptr;
  const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
  return j.is_object() && j.contains("status") ? j["status"] : nlohmann::json(nullptr);
}

ProcessResult Daemon::wait() {
  collected_ = true;
  return process_->wait();
}

RawClient::RawClient(const std::string& socket) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", socket.c_str());
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0 || connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    throw std::runtime_error(socket + ": cannot connect: " + std::strerror(errno));
  }
}

RawClient::~RawClient() { close(fd_); }

bool RawClient::send(const std::string& bytes) const {
  for (std::size_t sent = 0; sent < bytes.size();) {
    const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

std::string RawClient::line(int timeout_ms) {
  char buf[65536];
  for (;;) {
    if (const auto nl = in_.find('\n'); nl != std::string::npos) {
      std::string l = in_.substr(0, nl);
      in_.erase(0, nl + 1);
      return l;
    }
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return "";
    const ssize_t n = recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) return "";
    in_.append(buf, static_cast<std::size_t>(n));
  }
}

bool RawClient::closed_by_peer(int timeout_ms) {
  char buf[65536];
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return false;
    const ssize_t n = recv(fd_, buf, sizeof buf, 0);
    if (n == 0 || (n < 0 && errno == ECONNRESET)) return true;
    if (n < 0) return false;
    in_.append(buf, static_cast<std::size_t>(n));
  }
}

}  // namespace hapticd::testing
