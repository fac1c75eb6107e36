#include <cmath>
#include <cstdint>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/config/demo_scene.hpp"
#include "flowsteer/launch/demo.hpp"

namespace flowsteer::cli {

namespace {

struct DemoCommand {
  std::string scene_file;
  std::vector<std::string> obstacles;
  std::vector<double> goal;
  std::optional<double> speed_mps;
  std::optional<int> resolution;
};

// "x,y,width[,vx,vy]": a box obstacle in the agent's body frame.
servo::SceneObject parse_obstacle(const std::string& text, std::int32_t id) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    try {
      std::size_t used = 0;
      values.push_back(std::stod(part, &used));
      if (used != part.size()) {
        throw std::invalid_argument(part);
      }
    } catch (const std::exception&) {
      throw CLI::ValidationError("--obstacle", "'" + part + "' in '" + text + "' is not a number");
    }
  }
  if (values.size() != 3 && values.size() != 5) {
    throw CLI::ValidationError("--obstacle", "'" + text + "' must be x,y,width or x,y,width,vx,vy");
  }
  if (!(values[2] > 0.0)) {
    throw CLI::ValidationError("--obstacle", "width in '" + text + "' must be positive");
  }
  servo::SceneObject o;
  o.id = id;
  o.position_m = {values[0], values[1]};
  o.length_m = values[2];
  o.width_m = values[2];
  if (values.size() == 5) {
    o.velocity_mps = {values[3], values[4]};
  }
  return o;
}

int run_demo(const DemoCommand& command) {
  config::DemoScene scene = command.scene_file.empty()
                                ? config::default_demo_scene()
                                : config::load_demo_scene(command.scene_file);
  if (!command.obstacles.empty()) {
    scene.scene.objects.clear();
    for (std::size_t i = 0; i < command.obstacles.size(); ++i) {
      scene.scene.objects.push_back(
          parse_obstacle(command.obstacles[i], static_cast<std::int32_t>(i + 1)));
    }
  }
  if (!command.goal.empty()) {
    scene.goal_m = Eigen::Vector2d(command.goal[0], command.goal[1]);
  }
  if (command.speed_mps) {
    scene.scene.agent_speed_mps = *command.speed_mps;
  }
  if (command.resolution) {
    const base::CameraIntrinsics& k = scene.scene.intrinsics;
    const double hfov = 2.0 * std::atan(0.5 * k.width_px / k.fx_px);
    scene.scene.intrinsics =
        base::CameraIntrinsics::from_horizontal_fov(*command.resolution, *command.resolution, hfov);
  }
  launch::run_demo(scene, std::cout);
  return 0;
}

}  // namespace

Subcommand add_demo(CLI::App& app) {
  auto command = std::make_shared<DemoCommand>();
  CLI::App* demo = app.add_subcommand(
      "demo",
      "Build a flow field analytically for a scene, run the servo core on it and print the "
      "features and the command");
  demo->add_option("--scene", command->scene_file,
                   "YAML scene (see launch/scenes/demo_street.yaml)");
  demo->add_option("--obstacle", command->obstacles,
                   "box obstacle x,y,width[,vx,vy] in metres and m/s, agent frame (x forward, "
                   "y left); replaces the scene's objects")
      ->take_all();
  demo->add_option("--goal", command->goal, "goal x y in metres, agent frame")
      ->expected(2)
      ->check(within(base::bounds::kPosition_m));
  demo->add_option("--speed", command->speed_mps, "agent speed in m/s")
      ->check(within(base::bounds::kSpeed_mps));
  demo->add_option("--resolution", command->resolution, "image width and height in pixels")
      ->check(within(base::bounds::kImageSide_px));
  return {demo, [command] { return run_demo(*command); }};
}

}  // namespace flowsteer::cli
