// A client's change to the walls of a running scene (docs/operations.md, scene requests): the
// running configuration's document with its `walls` edited, which the daemon then checks,
// gates and swaps in at a tick boundary exactly as a reload, and which running wall each new
// wall goes on from (its filters and its observer's energy). Pure: no daemon here.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "service/control/control_protocol.h"

namespace hapticd::service {

struct EditedScene {
  std::string yaml;            // the document, its walls edited
  std::vector<int> continues;  // new wall i goes on from running wall continues[i]; -1: new
  std::size_t index = 0;       // the wall added or changed (removed: the one that was)
};

// Not RT-safe. `document`: the running configuration as written (Config::effective_yaml).
// Throws ControlRefusal (exit code 2) naming what is wrong: an index past the walls, a wall
// that is not an object, a document without walls.
EditedScene edit_walls(const std::string& document, const SceneEdit& edit);

// Not RT-safe. The document without the walls at `gone` (each an index of its walls), and which
// wall each remaining one was. ControlRefusal as edit_walls.
EditedScene without_walls(const std::string& document, std::vector<std::size_t> gone);

}  // namespace hapticd::service
