// Builds a box of walls around the device where it is now (six walls for three task axes,
// four for two), holds it a moment, then removes the walls again, the last added first so each
// index still names its wall.
//
//   box_scene --socket /tmp/hapticd.sock --half 0.03
//
// Exit 0 when every wall was added and removed; a refusal's code otherwise (2 a bad argument).
#include <hapticd/client/connection.h>
#include <hapticd/client/state_reader.h>

#include "options.h"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

namespace hc = hapticd::client;
using Vec = std::vector<double>;

// (point, normal) of each face. Inside a wall is n . (x - point) > 0: the normals point out of
// the box, so the device inside it is outside every wall.
std::vector<std::pair<Vec, Vec>> box(const Vec& centre, double half) {
  std::vector<std::pair<Vec, Vec>> faces;
  for (std::size_t axis = 0; axis < centre.size(); ++axis) {
    for (const double sign : {1.0, -1.0}) {
      Vec point = centre, normal(centre.size(), 0.0);
      point[axis] += sign * half;
      normal[axis] = sign;
      faces.emplace_back(point, normal);
    }
  }
  return faces;
}

int usage() {
  std::fprintf(stderr,
               "usage: box_scene --socket PATH [--half M] [--stiffness N/M] "
               "[--damping NS/M] [--hold S]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  examples::Options o(argc, argv, {"--socket", "--half", "--stiffness", "--damping", "--hold"});
  const std::string socket = o.text("--socket");
  const double half = o.number("--half", 0.03), stiffness = o.number("--stiffness", 500.0),
               damping = o.number("--damping", 0.05), hold = o.number("--hold", 0.5);
  if (!o.ok() || socket.empty() || !(hold >= 0)) return usage();

  int code = 0;
  try {
    hc::Connection client(socket);
    Vec centre;
    {
      const hc::StateReader state = client.state();
      hc::StateSample sample;
      if (!state.latest(sample)) {
        std::fprintf(stderr, "box_scene: the loop has written no sample yet\n");
        return 1;
      }
      centre.assign(sample.x, sample.x + state.axes());
    }
    std::printf("box_scene: the device is at %s\n", examples::format(centre, 4).c_str());

    std::vector<std::size_t> added;
    try {
      for (const auto& [point, normal] : box(centre, half)) {
        const std::size_t index = client.add_wall(
            {{"point", point}, {"normal", normal}, {"stiffness", stiffness}, {"damping", damping}});
        added.push_back(index);
        std::printf("added wall %zu: point %s, normal %s\n", index,
                    examples::format(point, 4).c_str(), examples::format(normal, 4).c_str());
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(hold));
    } catch (const hc::Refused& e) {  // a wall refused: still take down those added
      std::fprintf(stderr, "box_scene: refused (code %d): %s\n", e.code(), e.what());
      code = e.code();
    }
    for (; !added.empty(); added.pop_back()) {
      const nlohmann::json scene = client.remove_wall(added.back());
      std::printf("removed wall %zu at tick %s (%s walls left)\n", added.back(),
                  scene.value("applied_at_tick", nlohmann::json()).dump().c_str(),
                  scene.value("walls", nlohmann::json()).dump().c_str());
    }
  } catch (const hc::Refused& e) {
    std::fprintf(stderr, "box_scene: refused (code %d): %s\n", e.code(), e.what());
    return e.code();
  } catch (const std::exception& e) {  // ClientError, or an answer not of the expected shape
    std::fprintf(stderr, "box_scene: %s\n", e.what());
    return 1;
  }
  if (code == 0) std::printf("box_scene: box built and removed\n");
  return code;
}
