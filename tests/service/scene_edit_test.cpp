// A scene request's edit of the running document (service/run/scene_edit.h): the walls after
// an add, a change and a removal, which running wall each new one goes on from, and the
// refusals that name what is wrong.
#include "service/run/scene_edit.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "service/control/control_server.h"

namespace hapticd::service {
namespace {

const char* const kDocument = R"(loop:
  rate_hz: 1000
walls:
  - {point: [0.02, 0, 0.11], normal: [1, 0, 0], stiffness: 500}
  - {point: [-0.02, 0, 0.11], normal: [-1, 0, 0], stiffness: 500}
  - {point: [0, 0.02, 0.11], normal: [0, 1, 0], stiffness: 500}
)";

YAML::Node walls_of(const EditedScene& e) { return YAML::Load(e.yaml)["walls"]; }

SceneEdit edit(SceneEdit::Op op, std::size_t index, const char* wall) {
  SceneEdit e;
  e.op = op;
  e.index = index;
  if (wall != nullptr) e.wall = nlohmann::json::parse(wall);
  return e;
}

TEST(SceneEdit, AddAppendsANewWallThatGoesOnFromNone) {
  const EditedScene e = edit_walls(
      kDocument, edit(SceneEdit::Op::kAdd, 0, R"({"point": [0, 0, 0.2], "normal": [0, 0, 1]})"));
  ASSERT_EQ(walls_of(e).size(), 4u);
  EXPECT_EQ(walls_of(e)[3]["point"][2].as<double>(), 0.2);
  EXPECT_EQ(e.continues, (std::vector<int>{0, 1, 2, -1}));
  EXPECT_EQ(e.index, 3u);
  EXPECT_EQ(YAML::Load(e.yaml)["loop"]["rate_hz"].as<int>(), 1000) << "the rest as it was";
}

TEST(SceneEdit, ChangeMergesOnlyTheKeysGivenAndTheWallGoesOnFromItself) {
  const EditedScene e =
      edit_walls(kDocument, edit(SceneEdit::Op::kChange, 1, R"({"stiffness": 300})"));
  ASSERT_EQ(walls_of(e).size(), 3u);
  EXPECT_EQ(walls_of(e)[1]["stiffness"].as<double>(), 300.0);
  EXPECT_EQ(walls_of(e)[1]["point"][0].as<double>(), -0.02) << "its point unchanged";
  EXPECT_EQ(walls_of(e)[0]["stiffness"].as<double>(), 500.0);
  EXPECT_EQ(e.continues, (std::vector<int>{0, 1, 2}));
}

TEST(SceneEdit, RemoveMovesTheLaterWallsDownAndEachGoesOnFromItsOldPlace) {
  const EditedScene e = edit_walls(kDocument, edit(SceneEdit::Op::kRemove, 0, nullptr));
  ASSERT_EQ(walls_of(e).size(), 2u);
  EXPECT_EQ(walls_of(e)[0]["point"][0].as<double>(), -0.02);
  EXPECT_EQ(e.continues, (std::vector<int>{1, 2}));
}

TEST(SceneEdit, AnIndexPastTheWallsOrADocumentWithoutWallsIsRefusedSayingSo) {
  try {
    edit_walls(kDocument, edit(SceneEdit::Op::kRemove, 3, nullptr));
    FAIL() << "walls[3] of three";
  } catch (const ControlRefusal& e) {
    EXPECT_EQ(e.code(), 2);
    EXPECT_STREQ(e.what(), "scene: \"index\": 3 names no wall (3 walls: 0..2)");
  }
  EXPECT_THROW(edit_walls("loop: {rate_hz: 1000}\n", edit(SceneEdit::Op::kAdd, 0, "{}")),
               ControlRefusal);
}

}  // namespace
}  // namespace hapticd::service
