// Reads every tick of the servo loop from the state block for a while and writes it as CSV
// (tick, time, x, v, f, contact), then says how many it read and how many it missed.
//
//   logger --socket /tmp/hapticd.sock --duration 2 --output ticks.csv
//
// Exit 0 when it read a sample, 1 otherwise, 2 a bad argument.
#include <hapticd/client/connection.h>
#include <hapticd/client/state_reader.h>
#include <time.h>

#include "options.h"

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

namespace {

namespace hc = hapticd::client;

std::int64_t monotonic_ns() {  // the clock of StateSample::time_ns
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// Shortest text that reads back as the same double, with no locale and no allocation.
template <typename T>
void put(std::string& line, T value) {
  char buf[32];
  const auto end = std::to_chars(buf, buf + sizeof buf, value).ptr;
  line.append(buf, end);
  line += ',';
}

int usage() {
  std::fprintf(stderr, "usage: logger --socket PATH [--duration S] [--output FILE.csv|-]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  examples::Options o(argc, argv, {"--socket", "--duration", "--output"});
  const std::string socket = o.text("--socket"), output = o.text("--output", "-");
  const double duration = o.number("--duration", 2.0);
  if (!o.ok() || socket.empty() || !(duration >= 0)) return usage();
  // The count goes where the CSV does not, so standard output stays CSV alone.
  std::FILE* report = output == "-" ? stderr : stdout;

  try {
    // The reader maps the block on its own: the connection is needed only to be handed it.
    hc::StateReader state = hc::Connection(socket).state();
    std::FILE* out = output == "-" ? stdout : std::fopen(output.c_str(), "w");
    if (out == nullptr) {
      std::perror(("logger: " + output).c_str());
      return 1;
    }
    const std::uint32_t axes = state.axes();
    std::string line = "tick,time_ns,";
    for (const char q : {'x', 'v', 'f'}) {
      for (std::uint32_t a = 0; a < axes; ++a) line += q + std::to_string(a) + ',';
    }
    line += "contact\n";
    std::fputs(line.c_str(), out);

    // Sleep only once caught up with the writer, 10 ms at a time: samples already there cost no
    // system call, and the block holds seconds of them, so every tick is read with 100 wake-ups
    // a second rather than one a tick (what 32 readers waking each tick would cost the loop's
    // CPUs: BENCHMARKS.md).
    constexpr std::int64_t poll_ns = 10'000'000;
    const std::int64_t until = monotonic_ns() + static_cast<std::int64_t>(duration * 1e9);
    std::uint64_t read = 0;
    for (hc::StateSample s;;) {
      if (!state.next(s)) {
        if (monotonic_ns() >= until) break;
        const timespec nap{0, static_cast<long>(poll_ns)};
        nanosleep(&nap, nullptr);
        continue;
      }
      if (s.time_ns >= until) break;
      ++read;
      line.clear();
      put(line, s.tick);
      put(line, s.time_ns);
      for (const double* q : {s.x, s.v, s.f}) {
        for (std::uint32_t a = 0; a < axes; ++a) put(line, q[a]);
      }
      line += std::to_string(s.wall_contact) + '\n';
      std::fputs(line.c_str(), out);
    }
    if (out != stdout && std::fclose(out) != 0) {
      std::perror(("logger: " + output).c_str());
      return 1;
    }
    std::fprintf(report, "logger: read %llu samples, missed %llu (%g ms period, %u slots)\n",
                 static_cast<unsigned long long>(read),
                 static_cast<unsigned long long>(state.missed()),
                 static_cast<double>(state.sample_period_ns()) / 1e6, state.slots());
    return read > 0 ? 0 : 1;
  } catch (const std::exception& e) {  // ClientError, Refused
    std::fprintf(stderr, "logger: %s\n", e.what());
    return 1;
  }
}
