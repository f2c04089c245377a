// The control socket of a running daemon (docs/operations.md): a Unix stream socket, mode 0660,
// group `hapticd` (the daemon's own group where there is no such group), one JSON object per
// line (control_protocol.h). It runs on its own thread and is non-blocking throughout, so no
// client - slow, silent, malicious - can stall the servo or the other clients: requests are
// bounded in size, a client that does not read its answers is dropped, an idle one is closed
// after kIdleSeconds, and at most kMaxClients are connected at once. A connection waiting in
// the listen backlog while every slot is taken gets the slot of the client that has been idle
// longest, once that one has been idle kEvictAfterMs: connections held open and silent cannot
// lock the others (the operator's `stop` among them) out. A caller that is not root, not the
// daemon's own user and not in the socket's group is refused at once, and the refusal is
// logged.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>

#include "service/control/control_protocol.h"

namespace hapticd::service {

// What answers the requests. handle() runs on the control socket's thread, one request at a
// time; its payload is merged into {"ok": true}; throwing ControlRefusal answers
// {"ok": false, "error": what(), "code": code()} (any other exception: code 1).
class ControlHandler {
 public:
  virtual ~ControlHandler() = default;
  virtual nlohmann::json handle(const Request& request) = 0;
  // The descriptor passed with the answer to `request` (SCM_RIGHTS, with its first byte), once
  // handle() answered it: -1 for none. The handler keeps owning it.
  virtual int descriptor(const Request& /*request*/) { return -1; }
  // Client `client` (Request::client) is gone: it closed, its connection failed, or the server
  // closed it. Not called for the clients still connected when the server stops.
  virtual void left(std::uint64_t /*client*/) {}
  // Whether `client` holds something of the daemon's (a scene's wall): the server then never
  // closes it for being idle or evicts it for a newcomer; only its own leaving ends it.
  virtual bool holds(std::uint64_t /*client*/) const { return false; }
  // Lines the daemon sends `client` unasked (a state stream), appended to `out`; `pending` is
  // what of its output is still unsent. Whether any were. Called every turn of the thread.
  virtual bool push(std::uint64_t /*client*/, std::size_t /*pending*/, std::string& /*out*/) {
    return false;
  }
  // How long the thread may wait before push() has lines again (ms); -1: never.
  virtual int push_wait_ms() const { return -1; }
};

class ControlRefusal : public std::runtime_error {
 public:
  explicit ControlRefusal(const std::string& what, int code = 1)
      : std::runtime_error(what), code_(code) {}
  int code() const noexcept { return code_; }

 private:
  int code_;
};

class ControlServer {
 public:
  static constexpr int kMaxClients = 32;
  static constexpr int kIdleSeconds = 60;
  static constexpr int kEvictAfterMs = 500;
  static constexpr std::size_t kMaxPendingOutput = 1 << 20;  // unread answers before a drop

  // Not RT-safe. Creates the socket at `path` (an existing socket file there is replaced;
  // anything else is refused), and starts its thread. Throws std::runtime_error naming the
  // path and the reason.
  ControlServer(const std::string& path, ControlHandler& handler);
  // Stops the thread and removes the socket file.
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  const std::string& path() const noexcept { return path_; }
  // Any thread: peers refused for their credentials so far.
  std::uint64_t refused_peers() const noexcept { return refused_.load(); }

 private:
  struct Client;
  void run() noexcept;
  bool allowed(int fd) const;
  void accept_clients(std::vector<Client>& clients);
  // Whether a client may connect now: a slot is free, or one can be freed (evict).
  bool room(const std::vector<Client>& clients) const;
  void evict_idlest(std::vector<Client>& clients);
  // Closes `c` and tells the handler it left.
  void end(Client& c);
  void serve(Client& c);
  // The handler's unasked lines for `c` (ControlHandler::push); whether any.
  bool push(Client& c);

  std::string path_;
  ControlHandler& handler_;
  int listen_fd_ = -1;
  int stop_fd_ = -1;
  gid_t group_ = 0;
  std::uint64_t next_client_ = 1;  // the server thread's: each connection's Request::client
  std::atomic<std::uint64_t> refused_{0};
  std::thread thread_;
};

}  // namespace hapticd::service
