#include "service/control/control_protocol.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

namespace hapticd::service {
namespace {

using nlohmann::json;

std::optional<Command> command_named(const std::string& name) {
  if (name == "status") return Command::kStatus;
  if (name == "stop") return Command::kStop;
  if (name == "reload") return Command::kReload;
  if (name == "clear-fault") return Command::kClearFault;
  if (name == "scene") return Command::kScene;
  if (name == "state") return Command::kState;
  if (name == "servo_cf") return Command::kServoCf;
  if (name == "stream") return Command::kStream;
  return std::nullopt;
}

// The scene requests' operations by name: what parse_scene reads and scene_op_name says.
constexpr std::pair<const char*, SceneEdit::Op> kSceneOps[] = {{"add", SceneEdit::Op::kAdd},
                                                               {"change", SceneEdit::Op::kChange},
                                                               {"remove", SceneEdit::Op::kRemove},
                                                               {"move", SceneEdit::Op::kMove}};

// A vector member `key` of 1 to 3 finite numbers (one per task axis, in `unit`); false with
// `error` naming what is wrong (`what` says what the request needs it for).
bool parse_vector(const json& j, const char* key, const std::string& what, const char* unit,
                  std::array<double, 3>& out, std::size_t& axes, std::string& error) {
  const auto v = j.find(key);
  if (v == j.end() || !v->is_array() || v->empty() || v->size() > 3) {
    error = what + " needs \"" + key + "\": one number per task axis (" + unit + ")";
    return false;
  }
  for (std::size_t a = 0; a < v->size(); ++a) {
    const json& x = (*v)[a];
    if (!x.is_number() || !std::isfinite(x.get<double>())) {
      error = what + ": \"" + key + "\"[" + std::to_string(a) + "]: must be a finite number (" +
              unit + "), got " + x.dump(-1, ' ', false, json::error_handler_t::replace);
      return false;
    }
    out[a] = x.get<double>();
  }
  axes = v->size();
  return true;
}

bool parse_point(const json& j, SceneEdit& out, std::string& error) {
  return parse_vector(j, "point", "scene: move", "m", out.point, out.axes, error);
}

// A scene request's members (control_protocol.h); false with `error` naming the member.
bool parse_scene(const json& j, SceneEdit& out, std::string& error) {
  const auto op = j.find("op");
  const std::string name = op != j.end() && op->is_string() ? op->get<std::string>() : "";
  const auto* known = std::find_if(std::begin(kSceneOps), std::end(kSceneOps),
                                   [&](const auto& o) { return name == o.first; });
  if (known == std::end(kSceneOps)) {
    error = "scene: \"op\" must be one of add, change, remove, move";
    return false;
  }
  out.op = known->second;
  if (out.op != SceneEdit::Op::kAdd) {
    const auto index = j.find("index");
    if (index == j.end() || !index->is_number_unsigned()) {
      error =
          std::string("scene: ") + name + " needs \"index\": the wall's place in walls (0, 1, ...)";
      return false;
    }
    out.index = index->get<std::size_t>();
  }
  if (out.op == SceneEdit::Op::kMove) return parse_point(j, out, error);
  if (const auto keep = j.find("keep"); keep != j.end()) {
    if (out.op != SceneEdit::Op::kAdd || !keep->is_boolean()) {
      error =
          "scene: \"keep\" is for add alone, true or false (whether the wall outlives its "
          "client)";
      return false;
    }
    out.keep = keep->get<bool>();
  }
  if (out.op != SceneEdit::Op::kRemove) {
    const auto wall = j.find("wall");
    if (wall == j.end() || !wall->is_object()) {
      error = std::string("scene: ") + name + " needs \"wall\": an object of a wall's keys";
      return false;
    }
    out.wall = *wall;
  }
  return true;
}

std::string line(json j) {
  // Invalid UTF-8 in an echoed id or a message is replaced, never an exception.
  return j.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

}  // namespace

std::optional<Request> parse_request(std::string_view text, std::string& error, json& id) {
  id = nullptr;
  if (text.size() > kMaxRequestBytes) {
    error = "request longer than " + std::to_string(kMaxRequestBytes) + " bytes";
    return std::nullopt;
  }
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) {
    error = "not a JSON object";
    return std::nullopt;
  }
  if (j.contains("id")) id = j["id"];
  const auto v = j.find("v");
  if (v == j.end() || !v->is_number_integer() || v->get<long long>() != kProtocolVersion) {
    error = "unsupported protocol version (this daemon speaks \"v\": 1)";
    return std::nullopt;
  }
  const auto cmd = j.find("cmd");
  const std::optional<Command> c =
      cmd != j.end() && cmd->is_string() ? command_named(cmd->get<std::string>()) : std::nullopt;
  if (!c) {
    error =
        "\"cmd\" must be one of status, stop, reload, clear-fault, scene, state, servo_cf, "
        "stream";
    return std::nullopt;
  }
  Request r;
  r.command = *c;
  r.id = id;
  if (*c == Command::kReload) {
    const auto config = j.find("config");
    if (config == j.end() || !config->is_string()) {
      error = "reload needs \"config\": the YAML text of the new configuration";
      return std::nullopt;
    }
    r.config_text = config->get<std::string>();
    const auto source = j.find("source");
    r.source = source != j.end() && source->is_string() ? source->get<std::string>() : "reload";
  }
  if (*c == Command::kScene && !parse_scene(j, r.scene, error)) return std::nullopt;
  if (*c == Command::kServoCf &&
      !parse_vector(j, "force", "servo_cf", "N", r.force, r.force_axes, error)) {
    return std::nullopt;
  }
  if (*c == Command::kStream) {
    const auto every = j.find("every");
    if (every == j.end() || !every->is_number_unsigned() ||
        every->get<std::uint64_t>() > kMaxStreamEvery) {
      error = "stream needs \"every\": an integer 1.." + std::to_string(kMaxStreamEvery) +
              " (a sample every that many ticks), or 0 to stop";
      return std::nullopt;
    }
    r.every = static_cast<std::uint32_t>(every->get<std::uint64_t>());
  }
  return r;
}

const char* scene_op_name(SceneEdit::Op op) noexcept {
  for (const auto& [name, o] : kSceneOps) {
    if (o == op) return name;
  }
  return "?";
}

std::string ok_response(const json& id, const json& payload) {
  json j = {{"v", kProtocolVersion}, {"id", id}, {"ok", true}};
  if (payload.is_object()) {
    for (auto it = payload.begin(); it != payload.end(); ++it) j[it.key()] = it.value();
  }
  return line(std::move(j));
}

std::string error_response(const json& id, const std::string& error, int code) {
  return line(
      {{"v", kProtocolVersion}, {"id", id}, {"ok", false}, {"error", error}, {"code", code}});
}

}  // namespace hapticd::service
