// Moves a wall along its normal by a sine, one move every 10 ms (100 Hz), and prints how long
// a move takes from the send to the tick that applied it (p50/p99/max). The sine is centred
// where the wall is when it starts (the status answer says each wall's point and normal):
//
//   sine_wall --socket /tmp/hapticd.sock --index 0 --amplitude 0.005 --frequency 0.5 --duration 3
//
// Exit 0 when every move was applied, 1 otherwise (a refusal's code when refused, 2 a bad
// argument).
#include <hapticd/client/connection.h>
#include <time.h>

#include "options.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <numbers>
#include <string>
#include <vector>

namespace {

namespace hc = hapticd::client;

// The daemon stamps applied_at_ns with CLOCK_MONOTONIC, so the send is timed on the same clock.
std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// An absolute deadline: the moves keep their 10 ms grid however long each one took.
void sleep_until(std::int64_t t_ns) {
  const timespec ts{static_cast<time_t>(t_ns / 1'000'000'000),
                    static_cast<long>(t_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// Nearest rank: a value that was measured, not an interpolation.
std::int64_t percentile(const std::vector<std::int64_t>& ordered, double q) {
  const auto rank = static_cast<std::ptrdiff_t>(std::ceil(q * static_cast<double>(ordered.size())));
  const auto last = static_cast<std::ptrdiff_t>(ordered.size()) - 1;
  return ordered[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(rank - 1, 0, last))];
}

int usage() {
  std::fprintf(stderr,
               "usage: sine_wall --socket PATH [--index N] [--point x,y,z] [--normal x,y,z]\n"
               "                 [--amplitude M] [--frequency HZ] [--duration S] [--rate HZ]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  examples::Options o(argc, argv,
                      {"--socket", "--index", "--point", "--normal", "--amplitude", "--frequency",
                       "--duration", "--rate"});
  const std::string socket = o.text("--socket");
  const double wall = o.number("--index", 0.0);
  // Empty: the wall's own point and normal.
  std::vector<double> point = o.numbers("--point"), normal = o.numbers("--normal");
  const double amplitude = o.number("--amplitude", 0.005);
  const double frequency = o.number("--frequency", 0.5);
  const double duration = o.number("--duration", 3.0), rate = o.number("--rate", 100.0);
  if (!o.ok() || socket.empty() || !(wall >= 0) || wall != static_cast<std::size_t>(wall) ||
      !(rate > 0) || !(duration >= 0)) {
    return usage();
  }
  const auto index = static_cast<std::size_t>(wall);

  std::vector<std::int64_t> latencies;
  int moves = 0, not_applied = 0, late = 0;
  try {
    hc::Connection client(socket);
    if (point.empty() || normal.empty()) {
      const nlohmann::json walls = client.status().value("walls", nlohmann::json::array());
      if (index >= walls.size()) {
        std::fprintf(stderr, "sine_wall: the daemon has %zu walls, no wall %zu\n", walls.size(),
                     index);
        return 2;
      }
      if (point.empty()) point = walls[index]["point"].get<std::vector<double>>();
      if (normal.empty()) normal = walls[index]["normal"].get<std::vector<double>>();
    }
    double norm = 0;
    for (const double n : normal) norm += n * n;
    norm = std::sqrt(norm);
    // A move carries as many numbers as the device has task axes: the wall's point has that many.
    if (point.size() != normal.size() || point.empty() || point.size() > 3 || norm == 0) {
      std::fprintf(stderr,
                   "sine_wall: --point and --normal: 1 to 3 numbers, as many each, "
                   "the normal not zero\n");
      return 2;
    }
    for (double& n : normal) n /= norm;

    const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / rate));
    moves = static_cast<int>(duration * rate);
    const std::int64_t start = monotonic_ns();
    for (int k = 0; k <= moves; ++k) {  // the last one puts the wall back where it was
      const std::int64_t due = start + k * period_ns;
      if (const std::int64_t now = monotonic_ns(); due > now) {
        sleep_until(due);
      } else if (now - due > period_ns) {
        ++late;
      }
      const double t = static_cast<double>(k * period_ns) / 1e9;
      const double s = k < moves ? amplitude * std::sin(2 * std::numbers::pi * frequency * t) : 0;
      std::vector<double> p(point.size());
      for (std::size_t a = 0; a < point.size(); ++a) p[a] = point[a] + s * normal[a];
      const std::int64_t sent = monotonic_ns();
      const hc::Applied applied = client.move_wall(index, p);
      if (applied.time_ns) {
        latencies.push_back(*applied.time_ns - sent);
      } else {
        ++not_applied;  // the output is off: the next arming takes the move
      }
    }
  } catch (const hc::Refused& e) {
    std::fprintf(stderr, "sine_wall: move refused (code %d): %s\n", e.code(), e.what());
    return e.code();
  } catch (const std::exception& e) {  // ClientError, or an answer not of the expected shape
    std::fprintf(stderr, "sine_wall: %s\n", e.what());
    return 1;
  }
  std::printf(
      "sine_wall: wall %zu moved %d times along %s by %g mm at %g Hz over %g s: "
      "%zu applied, %d not applied, %d sent late\n",
      index, moves + 1, examples::format(normal).c_str(), amplitude * 1e3, frequency, duration,
      latencies.size(), not_applied, late);
  if (!latencies.empty()) {
    std::sort(latencies.begin(), latencies.end());
    std::printf("send->applied latency: p50 %.1f us, p99 %.1f us, max %.1f us\n",
                static_cast<double>(percentile(latencies, 0.5)) / 1e3,
                static_cast<double>(percentile(latencies, 0.99)) / 1e3,
                static_cast<double>(latencies.back()) / 1e3);
  }
  return !latencies.empty() && not_applied == 0 ? 0 : 1;
}
