// The decimated state stream (docs/clients.md, the state stream): for a client that asks
// {"cmd": "stream", "every": N}, every N-th sample of the state block as a line of its own on
// the control socket, {"v": 1, "stream": {...}}, read off the RT thread from the block the loop
// already writes (client/state_reader.h): the loop does nothing more for any number of streams.
// A client that does not read its lines is not waited for: while more than kBacklogBytes of its
// output are unsent, and where the block's ring overtook the reader, samples are skipped and
// counted (each line's "missed"). Everything here runs on the control socket's thread alone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "client/state_reader.h"
#include "service/control/control_protocol.h"

namespace hapticd::service {

class StateStream {
 public:
  // Unsent output (bytes) beyond which a client's samples are counted missed, not queued.
  static constexpr std::size_t kBacklogBytes = 256 * 1024;

  // Maps the state block `block_fd` refers to (a descriptor of its own: `block_fd` stays the
  // caller's). Throws client::ClientError when it is not a state block.
  explicit StateStream(int block_fd);

  // The answer's "stream" member to {"cmd": "stream", "every": every}: every > 0 (re)starts
  // `client`'s stream from the next sample, 0 stops it (and says what it sent and missed).
  nlohmann::json subscribe(std::uint64_t client, std::uint32_t every);
  // `client` left: its stream ends.
  void leave(std::uint64_t client) { streams_.erase(client); }
  bool streaming(std::uint64_t client) const { return streams_.count(client) != 0; }
  // Appends `client`'s due samples to `out` (`pending`: its bytes not yet sent); whether any.
  bool push(std::uint64_t client, std::size_t pending, std::string& out);
  // How long the control socket's thread may sleep before a stream is due again (ms); -1: none.
  int wait_ms() const;

 private:
  struct Stream {
    std::uint32_t every = 1;
    std::uint64_t next = 0;  // the sample index due next
    std::uint64_t sent = 0;
    std::uint64_t missed = 0;
  };
  client::StateReader reader_;
  std::map<std::uint64_t, Stream> streams_;
};

}  // namespace hapticd::service
