#include "service/run/scene_edit.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <functional>

#include "service/control/control_server.h"
#include "service/exit_codes.h"

namespace hapticd::service {

namespace {

// A JSON value as a YAML node: JSON is YAML's flow style. ControlRefusal (code 2) for what
// yaml-cpp cannot take back.
YAML::Node node_of(const nlohmann::json& value) {
  try {
    return YAML::Load(value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  } catch (const YAML::Exception& e) {
    throw ControlRefusal(std::string("scene: \"wall\": not a wall's keys: ") + e.what(),
                         kExitUsage);
  }
}

}  // namespace

EditedScene edit_walls(const std::string& document, const SceneEdit& edit) {
  YAML::Node root = YAML::Load(document);
  YAML::Node walls = root.IsMap() ? root["walls"] : YAML::Node();
  if (!walls.IsSequence()) {
    throw ControlRefusal("scene: the running configuration has no walls list", kExitUsage);
  }
  const std::size_t n = walls.size();
  if (edit.op != SceneEdit::Op::kAdd && edit.index >= n) {
    throw ControlRefusal("scene: \"index\": " + std::to_string(edit.index) + " names no wall (" +
                             std::to_string(n) + " walls: 0.." + std::to_string(n - 1) + ")",
                         kExitUsage);
  }
  if (edit.op != SceneEdit::Op::kRemove && !edit.wall.is_object()) {
    throw ControlRefusal("scene: \"wall\" must be an object of a wall's keys (walls[i])",
                         kExitUsage);
  }
  EditedScene out;
  YAML::Node next(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < n; ++i) {
    if (edit.op == SceneEdit::Op::kRemove && i == edit.index) continue;
    YAML::Node wall = YAML::Clone(walls[i]);
    if (edit.op == SceneEdit::Op::kChange && i == edit.index) {
      for (auto it = edit.wall.begin(); it != edit.wall.end(); ++it) {
        wall[it.key()] = node_of(it.value());
      }
    }
    next.push_back(wall);
    out.continues.push_back(static_cast<int>(i));
  }
  out.index = edit.index;
  if (edit.op == SceneEdit::Op::kAdd) {
    next.push_back(node_of(edit.wall));
    out.continues.push_back(-1);
    out.index = n;
  }
  root["walls"] = next;
  YAML::Emitter text;
  text << root;
  out.yaml = text.c_str();
  return out;
}

EditedScene without_walls(const std::string& document, std::vector<std::size_t> gone) {
  std::sort(gone.begin(), gone.end(), std::greater<>());
  gone.erase(std::unique(gone.begin(), gone.end()), gone.end());
  EditedScene out;
  out.yaml = document;
  std::vector<int> was;                   // remaining wall i was wall was[i] of `document`
  for (const std::size_t index : gone) {  // the highest first: the lower keep their places
    SceneEdit edit;
    edit.op = SceneEdit::Op::kRemove;
    edit.index = index;
    EditedScene step = edit_walls(out.yaml, edit);
    if (was.empty()) {
      was = std::move(step.continues);
    } else {
      for (int& w : step.continues) w = was[static_cast<std::size_t>(w)];
      was = std::move(step.continues);
    }
    out.yaml = std::move(step.yaml);
  }
  out.continues = std::move(was);
  return out;
}

}  // namespace hapticd::service
