// The `flowsteer` command.
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "flowsteer/launch/config_error.hpp"
#include "flowsteer/launch/demo.hpp"
#include "flowsteer/launch/demo_scene.hpp"

namespace {

using flowsteer::launch::DemoScene;

// "x,y,width[,vx,vy]": a box obstacle in the agent's body frame.
flowsteer::servo::SceneObject parse_obstacle(const std::string& text, std::int32_t id) {
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
  flowsteer::servo::SceneObject o;
  o.id = id;
  o.position_m = {values[0], values[1]};
  o.length_m = values[2];
  o.width_m = values[2];
  if (values.size() == 5) {
    o.velocity_mps = {values[3], values[4]};
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"flowsteer: visual-servo steering from optical flow"};
  app.require_subcommand(1);

  CLI::App* demo = app.add_subcommand(
      "demo",
      "Build a flow field analytically for a scene, run the servo core on it and print the "
      "features and the command");
  std::string scene_file;
  std::vector<std::string> obstacles;
  std::vector<double> goal;
  double speed = -1.0;
  int resolution = 0;
  demo->add_option("--scene", scene_file, "YAML scene (see launch/scenes/demo_street.yaml)");
  demo->add_option("--obstacle", obstacles,
                   "box obstacle x,y,width[,vx,vy] in metres and m/s, agent frame (x forward, "
                   "y left); replaces the scene's objects")
      ->take_all();
  demo->add_option("--goal", goal, "goal x y in metres, agent frame")->expected(2);
  demo->add_option("--speed", speed, "agent speed in m/s")->check(CLI::NonNegativeNumber);
  demo->add_option("--resolution", resolution, "image width and height in pixels")
      ->check(CLI::Range(8, 4096));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  try {
    if (*demo) {
      DemoScene scene = scene_file.empty() ? flowsteer::launch::default_demo_scene()
                                           : flowsteer::launch::load_demo_scene(scene_file);
      if (!obstacles.empty()) {
        scene.scene.objects.clear();
        for (std::size_t i = 0; i < obstacles.size(); ++i) {
          scene.scene.objects.push_back(
              parse_obstacle(obstacles[i], static_cast<std::int32_t>(i + 1)));
        }
      }
      if (!goal.empty()) {
        scene.goal_m = Eigen::Vector2d(goal[0], goal[1]);
      }
      if (speed >= 0.0) {
        scene.scene.agent_speed_mps = speed;
      }
      if (resolution > 0) {
        const double hfov =
            2.0 * std::atan(0.5 * scene.scene.intrinsics.width_px / scene.scene.intrinsics.fx_px);
        scene.scene.intrinsics =
            flowsteer::servo::CameraIntrinsics::from_horizontal_fov(resolution, resolution, hfov);
      }
      flowsteer::launch::run_demo(scene, std::cout);
    }
  } catch (const CLI::ValidationError& e) {
    std::cerr << "flowsteer: " << e.what() << "\n";
    return 2;
  } catch (const flowsteer::launch::ConfigError& e) {
    std::cerr << "flowsteer: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "flowsteer: error: " << e.what() << "\n";
    return 1;
  }
  return EXIT_SUCCESS;
}
