#include "service/run/state_stream.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace hapticd::service {
namespace {

using nlohmann::json;

int own_copy(int fd) {
  const int copy = fcntl(fd, F_DUPFD_CLOEXEC, 0);
  if (copy < 0) {
    throw client::ClientError(std::string("state stream: dup of the state block: ") +
                              std::strerror(errno));
  }
  return copy;
}

json triple(const double (&v)[3], std::uint32_t n) {
  json a = json::array();
  for (std::uint32_t i = 0; i < n; ++i) a.push_back(v[i]);
  return a;
}

// One sample as its line, CRTK's names as the state block's (client/state_layout.h).
std::string sample_line(const client::StateSample& s, std::uint32_t joints, std::uint32_t axes,
                        std::uint64_t missed) {
  const json body = {{"tick", s.tick},
                     {"time_ns", s.time_ns},
                     {"measured_js",
                      {{"position", triple(s.q, joints)},
                       {"velocity", triple(s.qd, joints)},
                       {"effort", triple(s.effort, joints)}}},
                     {"measured_cp", triple(s.x, axes)},
                     {"measured_cv", triple(s.v, axes)},
                     {"setpoint_cf", triple(s.f, axes)},
                     {"observer_energy_j", s.observer_energy_j},
                     {"flags", s.flags},
                     {"wall_contact", s.wall_contact},
                     {"fault_cause", s.fault_cause},
                     {"missed", missed}};
  return json({{"v", 1}, {"stream", body}}).dump(-1, ' ', false, json::error_handler_t::replace) +
         "\n";
}

}  // namespace

StateStream::StateStream(int block_fd) : reader_(own_copy(block_fd)) {}

json StateStream::subscribe(std::uint64_t client, std::uint32_t every) {
  if (every == 0) {
    const auto it = streams_.find(client);
    json out = {{"every", 0},
                {"sent", it != streams_.end() ? it->second.sent : 0},
                {"missed", it != streams_.end() ? it->second.missed : 0}};
    if (it != streams_.end()) streams_.erase(it);
    return out;
  }
  Stream s;
  s.every = every;
  s.next = reader_.head();  // the next sample the loop writes
  streams_[client] = s;
  const double rate_hz = 1e9 / static_cast<double>(reader_.sample_period_ns());
  return {{"every", every}, {"rate_hz", rate_hz / every}, {"first_sample", s.next}};
}

bool StateStream::push(std::uint64_t client, std::size_t pending, std::string& out) {
  const auto it = streams_.find(client);
  if (it == streams_.end()) return false;
  Stream& s = it->second;
  const std::uint64_t head = reader_.head();
  if (head > s.next + reader_.slots()) {  // the ring went round: what it holds is all there is
    const std::uint64_t skipped = (head - reader_.slots() - s.next + s.every - 1) / s.every;
    s.missed += skipped;
    s.next += skipped * s.every;
  }
  bool any = false;
  while (s.next < head) {
    client::StateSample sample;
    const client::StateReader::Read r = pending + out.size() > kBacklogBytes
                                            ? client::StateReader::Read::kMissed
                                            : reader_.read(s.next, sample);
    if (r == client::StateReader::Read::kNotYet) break;
    if (r == client::StateReader::Read::kOk) {
      out += sample_line(sample, reader_.joints(), reader_.axes(), s.missed);
      ++s.sent;
      any = true;
    } else {
      ++s.missed;
    }
    s.next += s.every;
  }
  return any;
}

int StateStream::wait_ms() const {
  if (streams_.empty()) return -1;
  auto every = static_cast<std::uint32_t>(kMaxStreamEvery);
  for (const auto& [client, s] : streams_) every = std::min(every, s.every);
  const double ms =
      static_cast<double>(every) * static_cast<double>(reader_.sample_period_ns()) / 1e6;
  return std::clamp(static_cast<int>(ms), 1, 1000);
}

}  // namespace hapticd::service
