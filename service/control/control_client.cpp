#include "service/control/control_client.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "base/errno_text.h"
#include "service/control/control_protocol.h"

namespace hapticd::service {
namespace {

// Closes the descriptor on every way out.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

ClientError failure(const std::string& socket, const std::string& what, int err) {
  return ClientError(socket + ": " + what + ": " + base::errno_text(err));
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

// Reads up to the first newline, within the deadline.
std::string receive_line(int fd, const std::string& socket, int timeout_ms) {
  using clock = std::chrono::steady_clock;
  const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
  std::string in;
  char buf[65536];
  for (;;) {
    if (const auto nl = in.find('\n'); nl != std::string::npos) return in.substr(0, nl);
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
    if (left <= 0) {
      throw ClientError(socket + ": no answer within " + std::to_string(timeout_ms) + " ms");
    }
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(left)) < 0 && errno != EINTR) {
      throw failure(socket, "poll", errno);
    }
    if (p.revents == 0) continue;
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw failure(socket, "cannot read the answer", errno);
    if (n == 0) throw ClientError(socket + ": the daemon closed the connection without an answer");
    in.append(buf, static_cast<std::size_t>(n));
  }
}

}  // namespace

std::string instance_socket(const std::string& name) {
  return "/run/hapticd/" + name + "/control.sock";
}

nlohmann::json request(const std::string& socket, nlohmann::json request, int timeout_ms) {
  request["v"] = kProtocolVersion;
  const Fd fd{connect_to(socket)};
  const std::string text =
      request.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  std::string line;
  if (const int err = send_all(fd.fd, text); err != 0) {
    // A daemon that refuses this peer answers at once and hangs up, maybe before the request
    // was sent: its answer is still there to read.
    try {
      line = receive_line(fd.fd, socket, 1000);
    } catch (const ClientError&) {
      throw failure(socket, "cannot send the request", err);
    }
  } else {
    line = receive_line(fd.fd, socket, timeout_ms);
  }
  nlohmann::json answer = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (answer.is_discarded() || !answer.is_object() || !answer.contains("ok")) {
    throw ClientError(socket +
                      ": the answer is not a control-protocol object: " + line.substr(0, 200));
  }
  return answer;
}

}  // namespace hapticd::service
