// The client side of the control socket (control_protocol.h), for hapticctl and the tests: one
// request, one answer. Blocking, with a time-out; not for the daemon's own threads.
#pragma once

#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace hapticd::service {

// The socket could not be reached, or gave no well-formed answer: what() names the socket and
// what went wrong ("/run/hapticd/x.sock: cannot connect: No such file or directory").
class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The socket of instance `name` of the template unit hapticd@.service:
// /run/hapticd/NAME/control.sock.
std::string instance_socket(const std::string& name);

// Connects to `socket`, sends `request` (its "v" is set) as one line and returns the one-line
// answer parsed. Throws ClientError when it cannot connect, the daemon hangs up without an
// answer, the answer is not JSON, or none arrives within `timeout_ms`.
nlohmann::json request(const std::string& socket, nlohmann::json request, int timeout_ms);

}  // namespace hapticd::service
