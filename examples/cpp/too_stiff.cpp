// Asks for a wall far stiffer than the device can render passively and shows the passivity
// gate refusing it, with the gate's numbers.
//
//   too_stiff --socket /tmp/hapticd.sock --stiffness 1e7
//
// Exit 0 when the gate refused it, 1 when it was accepted (then it is removed again) or
// refused for another reason, 2 a bad argument.
#include <hapticd/client/connection.h>

#include "options.h"

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

namespace {

namespace hc = hapticd::client;

constexpr int kGateRefused = 3;  // the daemon's code for a refusal by the passivity gate

// A point 1 cm from the device along `normal`: the wall's face is within reach and the device
// is outside the wall (inside is n . (x - point) > 0). A wall out of reach is passive at any
// stiffness, and the gate would rightly let it in.
std::vector<double> beyond_device(hc::Connection& client, const std::vector<double>& normal) {
  const nlohmann::json status = client.status();
  const nlohmann::json x = status.value("task_position", nlohmann::json());
  const nlohmann::json joints = status.value("joints", nlohmann::json());
  if (!x.is_array() || !joints.is_array() || x.size() < joints.size()) {
    throw hc::ClientError("status has no task_position (a device of one joint?): give --point");
  }
  // task_position has three numbers; the device's task axes are as many as its joints.
  std::vector<double> point = x.get<std::vector<double>>();
  point.resize(joints.size());
  double norm = 0;
  for (const double n : normal) norm += n * n;
  norm = std::sqrt(norm);
  if (point.size() != normal.size() || norm == 0) {
    throw hc::ClientError("--normal: as many numbers as the device's " +
                          std::to_string(point.size()) + " task axes, not zero");
  }
  for (std::size_t a = 0; a < point.size(); ++a) point[a] += 0.01 * normal[a] / norm;
  return point;
}

int usage() {
  std::fprintf(stderr,
               "usage: too_stiff --socket PATH [--stiffness N/M] [--damping NS/M]\n"
               "                 [--point x,y,z] [--normal nx,ny,nz]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  examples::Options o(argc, argv, {"--socket", "--stiffness", "--damping", "--point", "--normal"});
  const std::string socket = o.text("--socket");
  const double stiffness = o.number("--stiffness", 1e7), damping = o.number("--damping", 0.05);
  std::vector<double> point = o.numbers("--point");
  const std::vector<double> normal = o.numbers("--normal", {0.0, 0.0, 1.0});
  if (!o.ok() || socket.empty()) return usage();

  try {
    hc::Connection client(socket);
    if (point.empty()) point = beyond_device(client, normal);
    std::size_t index = 0;
    try {
      index = client.add_wall(
          {{"point", point}, {"normal", normal}, {"stiffness", stiffness}, {"damping", damping}});
    } catch (const hc::Refused& e) {
      if (e.code() != kGateRefused) {
        std::printf("too_stiff: refused, but not by the gate (code %d): %s\n", e.code(), e.what());
        return 1;
      }
      std::printf("too_stiff: a %g N/m wall was refused as expected (code %d): %s\n", stiffness,
                  e.code(), e.what());
      return 0;
    }
    std::printf("too_stiff: a %g N/m wall was ACCEPTED as wall %zu: removing it\n", stiffness,
                index);
    client.remove_wall(index);
    return 1;
  } catch (const std::exception& e) {  // ClientError, or the removal refused
    std::fprintf(stderr, "too_stiff: %s\n", e.what());
    return 1;
  }
}
