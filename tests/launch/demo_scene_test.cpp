#include "flowsteer/config/demo_scene.hpp"

#include <sstream>

#include <gtest/gtest.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/launch/demo.hpp"

namespace flowsteer::config {
namespace {

using launch::run_demo;

// The message of the base::ConfigError that parsing `yaml` throws.
std::string error_of(const std::string& yaml) {
  try {
    parse_demo_scene(yaml, "scene.yaml");
  } catch (const base::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << yaml;
  return "";
}

TEST(DemoScene, ExampleFileLoads) {
  const DemoScene d = load_demo_scene(FLOWSTEER_SCENES_DIR "/demo_street.yaml");
  EXPECT_EQ(d.scene.intrinsics.width_px, 160);
  EXPECT_EQ(d.scene.intrinsics.height_px, 120);
  ASSERT_EQ(d.scene.objects.size(), 3U);
  EXPECT_EQ(d.scene.objects[2].shape, servo::SceneObject::Shape::box);
  EXPECT_DOUBLE_EQ(d.scene.objects[2].velocity_mps.y(), -4.0);
  ASSERT_TRUE(d.goal_m.has_value());
  EXPECT_DOUBLE_EQ(d.goal_m->x(), 25.0);
}

TEST(DemoScene, ErrorsNameFileLineColumnAndField) {
  EXPECT_EQ(error_of("objects:\n  - {position: [1, 2], radius_m: -1, shape: cylinder}\n"),
            "scene.yaml:2:34: objects[0].radius_m: must be from 0.001 to 100 m, got -1");
  EXPECT_EQ(error_of("camera:\n  hfov: 90\n"),
            "scene.yaml:2:3: camera.hfov: unknown key (expected one of: resolution, hfov_deg, "
            "height_m, pitch_deg)");
  EXPECT_EQ(error_of("agent:\n  speed_mps: fast\n"),
            "scene.yaml:2:14: agent.speed_mps: expected a finite number, got 'fast'");
  EXPECT_NE(error_of("objects: [\n").find("scene.yaml:"), std::string::npos);
  EXPECT_NE(error_of("objects:\n  - {shape: cone, position: [1, 1]}\n")
                .find("objects[0].shape: expected one of: box, cylinder; got 'cone'"),
            std::string::npos);
  EXPECT_NE(error_of("objects:\n  - {size: [1, 1]}\n").find("objects[0].position: missing"),
            std::string::npos);
  EXPECT_NE(error_of("controller: {kind: following}\n").find("controller.leader: missing"),
            std::string::npos);
  EXPECT_NE(error_of("controller: {gamma: 0.5, delta: 1}\n").find("controller.delta"),
            std::string::npos);
  EXPECT_NE(error_of("objects:\n  - {id: 4, position: [5, 0]}\n  - {id: 4, position: [7, 0]}\n")
                .find("scene.yaml:3:5: objects[1].id: id 4 is used twice"),
            std::string::npos);
  EXPECT_NE(error_of("objects:\n  - {position: [0, 0]}\n").find("the camera is inside it"),
            std::string::npos);
  EXPECT_NE(error_of("- 1\n- 2\n").find("expected a mapping"), std::string::npos);
}

TEST(DemoScene, MissingFileIsNamed) {
  try {
    load_demo_scene("/nonexistent/scene.yaml");
    FAIL() << "expected an error";
  } catch (const base::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
}

TEST(Demo, DefaultSceneSeesEveryObjectAndSteers) {
  std::ostringstream out;
  run_demo(default_demo_scene(), out);
  const std::string text = out.str();
  EXPECT_NE(text.find("command: a_c = "), std::string::npos) << text;
  for (const char* term : {"heading", "approach_speed", "clearance", "braking", "anticipation"}) {
    EXPECT_NE(text.find(term), std::string::npos) << term;
  }
  // The post stands right of the heading, close: the agent turns left around it.
  EXPECT_NE(text.find("turns left"), std::string::npos) << text;
}

}  // namespace
}  // namespace flowsteer::config
