#include "service/control/control_server.h"

#include <grp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <string_view>
#include <utility>
#include <vector>

#include "base/errno_text.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::service {

struct ControlServer::Client {
  int fd = -1;
  std::uint64_t id = 0;  // Request::client
  std::string in;
  std::string out;
  bool closing = false;  // its input ended: close once every line is answered and written
  bool gone = false;     // it cannot take answers any more (it closed, or a send failed)
  // Answers that carry a descriptor: where each starts in `out`, and the descriptor.
  std::deque<std::pair<std::size_t, int>> passing;
  std::chrono::steady_clock::time_point last_active = std::chrono::steady_clock::now();
};

namespace {

std::runtime_error failure(const std::string& path, const std::string& what) {
  return std::runtime_error(path + ": control socket: " + what + ": " + base::errno_text(errno));
}

// The socket's group: `hapticd` where the system has it (the service's group), else ours.
gid_t socket_group() {
  if (const group* g = getgrnam("hapticd")) return g->gr_gid;
  return getegid();
}

// Whether the peer on `fd` had `gid` among its supplementary groups when it connected
// (SO_PEERGROUPS: the kernel's record of the connecting process, not a later look at /proc).
bool peer_in_group(int fd, gid_t gid) {
  std::vector<gid_t> groups(64);
  for (int attempt = 0; attempt < 2; ++attempt) {
    auto len = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
    if (getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &len) == 0) {
      groups.resize(len / sizeof(gid_t));
      return std::find(groups.begin(), groups.end(), gid) != groups.end();
    }
    if (errno != ERANGE) return false;
    groups.resize(len / sizeof(gid_t) + 1);  // len now says how many there are
  }
  return false;
}

std::string group_name(gid_t gid) {
  if (const group* g = getgrgid(gid)) return g->gr_name;
  return std::to_string(gid);
}

// An error that only says "not now" (the socket is non-blocking), not that the client is gone.
bool not_now(int err) { return err == EAGAIN || err == EWOULDBLOCK || err == EINTR; }

// Whether something accepts connections at addr (a stale socket file refuses them).
bool socket_answers(const sockaddr_un& addr) {
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  const bool answers = connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
  close(fd);
  return answers;
}

}  // namespace

ControlServer::ControlServer(const std::string& path, ControlHandler& handler)
    : path_(path), handler_(handler), group_(socket_group()) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) {
    errno = ENAMETOOLONG;
    throw failure(path, "path too long");
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  struct stat st {};
  if (lstat(path.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode)) {
      errno = EEXIST;
      throw failure(path, "something that is not a socket is there");
    }
    if (socket_answers(addr)) {  // a live daemon's: taking it over would orphan that one
      errno = EADDRINUSE;
      throw failure(path, "another process is serving this socket");
    }
    unlink(path.c_str());  // a stale socket of an earlier run
  }
  listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw failure(path, "socket");
  // Mode and group before listen(): no connection is possible before they hold.
  // chown only when the group is not ours already: the service runs in group hapticd, and its
  // system-call filter has no chown.
  if (bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
      chmod(path.c_str(), 0660) != 0 ||
      (group_ != getegid() && chown(path.c_str(), static_cast<uid_t>(-1), group_) != 0) ||
      listen(listen_fd_, 128) != 0) {
    const int err = errno;
    close(listen_fd_);
    errno = err;
    throw failure(path, "bind/chmod/chown/listen");
  }
  stop_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (stop_fd_ < 0) {
    const int err = errno;
    close(listen_fd_);
    unlink(path.c_str());
    errno = err;
    throw failure(path, "eventfd");
  }
  thread_ = std::thread([this] { run(); });
  pthread_setname_np(thread_.native_handle(), "hapticd-ctl");
}

ControlServer::~ControlServer() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(stop_fd_, &one, sizeof one);
  if (thread_.joinable()) thread_.join();
  close(stop_fd_);
  close(listen_fd_);
  unlink(path_.c_str());
}

bool ControlServer::allowed(int fd) const {
  ucred peer{};
  socklen_t len = sizeof peer;
  if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &peer, &len) != 0) {
    spdlog::warn("control socket: refused a client whose credentials cannot be read: {}",
                 base::errno_text(errno));
    return false;
  }
  if (peer.uid == 0 || peer.uid == geteuid() || peer.gid == group_ || peer_in_group(fd, group_)) {
    return true;
  }
  spdlog::warn(
      "control socket: refused pid {} uid {} gid {}: not root, not uid {} and not in group {}",
      peer.pid, peer.uid, peer.gid, geteuid(), group_name(group_));
  return false;
}

namespace {

// The client idle longest that may give up its slot: one with nothing left to send it, holding
// nothing of the daemon's.
template <typename Clients>
auto idlest(Clients& clients, const ControlHandler& handler) {
  const auto now = std::chrono::steady_clock::now();
  auto best = clients.end();
  for (auto it = clients.begin(); it != clients.end(); ++it) {
    if (!it->out.empty() || it->in.find('\n') != std::string::npos) continue;
    if (handler.holds(it->id)) continue;
    if (now - it->last_active < std::chrono::milliseconds(ControlServer::kEvictAfterMs)) continue;
    if (best == clients.end() || it->last_active < best->last_active) best = it;
  }
  return best;
}

}  // namespace

bool ControlServer::room(const std::vector<Client>& clients) const {
  return clients.size() < static_cast<std::size_t>(kMaxClients) ||
         idlest(clients, handler_) != clients.end();
}

void ControlServer::evict_idlest(std::vector<Client>& clients) {
  const auto it = idlest(clients, handler_);
  if (it == clients.end()) return;
  end(*it);
  clients.erase(it);
}

void ControlServer::end(Client& c) {
  close(c.fd);
  c.fd = -1;
  try {
    handler_.left(c.id);
  } catch (const std::exception& e) {
    spdlog::error("control socket {}: a client left and that failed: {}", path_, e.what());
  }
}

void ControlServer::accept_clients(std::vector<Client>& clients) {
  while (room(clients)) {
    const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // EAGAIN: no more waiting
    if (clients.size() >= static_cast<std::size_t>(kMaxClients)) evict_idlest(clients);
    if (!allowed(fd)) {
      refused_.fetch_add(1);
      const std::string no =
          error_response(nullptr, "permission denied: not in group " + group_name(group_));
      [[maybe_unused]] const ssize_t n = send(fd, no.data(), no.size(), MSG_NOSIGNAL);
      close(fd);
      continue;
    }
    clients.push_back(
        Client{fd, next_client_++, {}, {}, false, false, {}, std::chrono::steady_clock::now()});
  }
}

// Reads what the client sent, answers up to kLinesPerTurn complete lines (so one client's
// flood of requests cannot monopolise the thread: the others get their turn), and writes what
// it can.
void ControlServer::serve(Client& c) {
  constexpr int kLinesPerTurn = 8;
  char buf[65536];
  // Lines already buffered are answered first: a client that floods requests waits in its
  // socket, its buffer here stays bounded.
  if (!c.closing && c.in.size() <= kMaxRequestBytes) {
    const ssize_t n = recv(c.fd, buf, sizeof buf, 0);
    if (n > 0) {
      c.in.append(buf, static_cast<std::size_t>(n));
      c.last_active = std::chrono::steady_clock::now();
    } else if (n == 0) {
      c.closing = true;  // end of input: answer what came, then hang up
    } else if (!not_now(errno)) {
      c.gone = true;
      return;
    }
  }
  std::size_t nl = 0;
  for (int turn = 0; turn < kLinesPerTurn && (nl = c.in.find('\n')) != std::string::npos; ++turn) {
    const std::string line = c.in.substr(0, nl);
    c.in.erase(0, nl + 1);
    std::string error;
    nlohmann::json id;
    std::optional<Request> r = parse_request(line, error, id);
    if (!r) {
      c.out += error_response(id, error, 2);
      continue;
    }
    r->client = c.id;
    try {
      std::string answer = ok_response(r->id, handler_.handle(*r));
      if (const int fd = handler_.descriptor(*r); fd >= 0) c.passing.emplace_back(c.out.size(), fd);
      c.out += answer;
    } catch (const ControlRefusal& e) {
      c.out += error_response(r->id, e.what(), e.code());
    } catch (const std::exception& e) {
      c.out += error_response(r->id, e.what());
    }
  }
  if (c.in.size() > kMaxRequestBytes && c.in.find('\n') == std::string::npos) {
    // A line that never ends: answer and hang up.
    c.out += error_response(
        nullptr, "request longer than " + std::to_string(kMaxRequestBytes) + " bytes", 2);
    c.in.clear();
    c.closing = true;
  }
  while (!c.out.empty()) {
    // An answer that carries a descriptor starts a send of its own, which passes it.
    const bool passes = !c.passing.empty() && c.passing.front().first == 0;
    std::size_t length = c.out.size();
    if (!c.passing.empty()) {
      const std::size_t end = passes && c.passing.size() > 1 ? c.passing[1].first : length;
      length = passes ? end : c.passing.front().first;
    }
    const std::string_view bytes(c.out.data(), length);
    const ssize_t n =
        passes ? io::send_with_fd(c.fd, bytes.data(), bytes.size(), c.passing.front().second)
               : send(c.fd, bytes.data(), bytes.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0 && !not_now(errno)) {
      c.gone = true;  // EPIPE, ECONNRESET: what it asked can no longer be answered
      return;
    }
    if (n <= 0) break;
    if (passes) c.passing.pop_front();  // gone with the first byte
    const auto sent = static_cast<std::size_t>(n);
    for (auto& [at, fd] : c.passing) at -= sent;
    c.out.erase(0, sent);
  }
}

bool ControlServer::push(Client& c) {
  try {
    return handler_.push(c.id, c.out.size(), c.out);
  } catch (const std::exception& e) {
    spdlog::error("control socket {}: a line for client {} failed: {}", path_, c.id, e.what());
    return false;
  }
}

void ControlServer::run() noexcept {
  std::vector<Client> clients;
  std::vector<pollfd> fds;
  try {
    for (;;) {
      // While every slot is taken, new connections wait in the backlog (not polled: a ready
      // listening socket that is never accepted from would make poll return at once).
      const bool space = room(clients);
      fds.assign({{stop_fd_, POLLIN, 0}, {listen_fd_, static_cast<short>(space ? POLLIN : 0), 0}});
      for (const Client& c : clients) {
        // A client whose input ended is not polled for input: its end of file would make
        // poll return at once, forever, while it does not read its answers.
        const int in = c.closing ? 0 : POLLIN, out = c.out.empty() ? 0 : POLLOUT;
        fds.push_back({c.fd, static_cast<short>(in | out), 0});
      }
      // Lines already buffered are answered without waiting for more input.
      const bool queued = std::any_of(clients.begin(), clients.end(), [](const Client& c) {
        return c.in.find('\n') != std::string::npos;
      });
      // Full: look again soon, for a slot that becomes free to evict; a stream: when it is due.
      int wait_ms = queued ? 0 : (space ? 1000 : 100);
      if (const int push = handler_.push_wait_ms(); push >= 0) wait_ms = std::min(wait_ms, push);
      if (poll(fds.data(), fds.size(), wait_ms) < 0 && errno != EINTR) break;
      if (fds[0].revents != 0) break;
      if (fds[1].revents & POLLIN) accept_clients(clients);
      const auto now = std::chrono::steady_clock::now();
      for (std::size_t i = 0; i < clients.size(); ++i) {
        Client& c = clients[i];
        const short ev = i + 2 < fds.size() ? fds[i + 2].revents : 0;
        const bool pushed = !c.closing && push(c);
        if ((ev & (POLLIN | POLLOUT)) || pushed || c.in.find('\n') != std::string::npos) serve(c);
        const bool idle =
            now - c.last_active > std::chrono::seconds(kIdleSeconds) && !handler_.holds(c.id);
        // POLLHUP: it closed both ways (not a half-close), so no answer can reach it; kept, it
        // would hold a slot it can never give up and make poll return at once until idle.
        const bool gone = c.gone || (ev & (POLLHUP | POLLERR));
        // A client that ended its input is answered every complete line it sent before the
        // hang-up, not only those of the turn its end of input arrived in.
        const bool answered = c.out.empty() && c.in.find('\n') == std::string::npos;
        if (gone || idle || c.out.size() > kMaxPendingOutput || (c.closing && answered)) end(c);
      }
      std::erase_if(clients, [](const Client& c) { return c.fd < 0; });
    }
  } catch (const std::exception& e) {
    spdlog::error("control socket {}: stopped: {}", path_, e.what());
  }
  for (const Client& c : clients) close(c.fd);
}

}  // namespace hapticd::service
