// The control socket's protocol, version 1 (docs/operations.md): one JSON object per line in
// each direction, at most kMaxRequestBytes a line. Pure: no sockets here, so it is tested on
// its own.
//
// Request:  {"v": 1, "cmd": "status" | "stop" | "reload" | "clear-fault" | "state", "id": <any>,
//            "config": "<YAML text>", "source": "<name for messages>"}    (config: reload only)
//           {"v": 1, "cmd": "scene", "op": "add" | "change" | "remove", "index": <n>,
//            "wall": {<a wall's keys>}}      (a device of several joints; index: change, remove)
//            add may say "keep": true | false (the wall outlives its client or not)
//           {"v": 1, "cmd": "scene", "op": "move", "index": <n>, "point": [x, y, z]}
//                                            (1 to 3 finite numbers: the wall's new point, m)
//           {"v": 1, "cmd": "servo_cf", "force": [fx, fy, fz]}   (N, one per task axis)
//           {"v": 1, "cmd": "stream", "every": <n>}  (every n-th tick's state as a line of its
//            own, {"v": 1, "stream": {...}}, until 0 stops it: service/run/state_stream.h)
// "state" is answered with the state block's shape, and its descriptor passed with the answer's
// first byte (SCM_RIGHTS; client/state_layout.h).
// Response: {"v": 1, "id": <echoed>, "ok": true, ...the command's members}
//           {"v": 1, "id": <echoed>, "ok": false, "error": "<why>", "code": <exit code>}
// `code` is the exit code of docs/operations.md a client reports for the failure: 2 a malformed
// request or an invalid configuration (or one that needs a restart), 3 the gate refused it,
// 1 anything else (no fault to clear, a device that faults again, permission denied).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "client/connection.h"

namespace hapticd::service {

inline constexpr int kProtocolVersion = client::kProtocolVersion;  // one version, both ends
inline constexpr std::size_t kMaxRequestBytes = 256 * 1024;        // a configuration fits with room

enum class Command { kStatus, kStop, kReload, kClearFault, kScene, kState, kServoCf, kStream };
inline constexpr std::uint64_t kMaxStreamEvery = 100000;  // the longest decimation (ticks)

// A scene request: a change to the walls of the running scene.
struct SceneEdit {
  enum class Op { kAdd, kChange, kRemove, kMove };
  Op op = Op::kAdd;
  std::size_t index = 0;          // change, remove, move: which wall (walls[index])
  nlohmann::json wall;            // add: the new wall's keys; change: the keys that change
  std::array<double, 3> point{};  // move: the new point (m), finite; zero past `axes`
  std::size_t axes = 0;           // move: how many numbers "point" held (1 to 3)
  // add: whether the wall outlives the client that added it ("keep"); none: as
  // safety.client_walls_on_leave says.
  std::optional<bool> keep;
};

// "add", "change", "remove", "move".
const char* scene_op_name(SceneEdit::Op op) noexcept;

struct Request {
  Command command = Command::kStatus;
  nlohmann::json id;              // echoed in the response; null when absent
  std::string config_text;        // reload
  std::string source;             // reload: the name messages about the configuration use
  SceneEdit scene;                // scene
  std::array<double, 3> force{};  // servo_cf: the force (N), finite; zero past force_axes
  std::size_t force_axes = 0;
  std::uint32_t every = 0;   // stream: a sample every this many ticks, 0: stop
  std::uint64_t client = 0;  // the connection it came on (the server's number; 0: none)
};

// Parses one line (without its newline). On a malformed request returns nothing and sets
// `error` (and `id` when the line had a readable one), for an error response.
std::optional<Request> parse_request(std::string_view line, std::string& error, nlohmann::json& id);

// {"v":1,"id":id,"ok":true} merged with `payload`'s members, as one line with its newline.
std::string ok_response(const nlohmann::json& id, const nlohmann::json& payload = {});
std::string error_response(const nlohmann::json& id, const std::string& error, int code = 1);

}  // namespace hapticd::service
