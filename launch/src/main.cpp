// The `flowsteer` command.
#include <unistd.h>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "flowsteer/launch/calibrate.hpp"
#include "flowsteer/launch/camera_source.hpp"
#include "flowsteer/eval/compare.hpp"
#include "flowsteer/base/config_error.hpp"
#include "flowsteer/launch/demo.hpp"
#include "flowsteer/config/demo_scene.hpp"
#include "flowsteer/eval/flow_evaluation.hpp"
#include "flowsteer/launch/robot_commands.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/eval/robustness.hpp"
#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/eval/simulation.hpp"

namespace {

using flowsteer::config::DemoScene;

// Set by SIGINT / SIGTERM: the robot loop sees it, stops the base and returns.
std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free);

void request_stop(int) {
  g_stop_requested.store(true);
}

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// The flow method `name`, the value of `option`; CLI::ValidationError "unknown <noun> 'NAME'
// (known: <known>)" when no method has that name or, with refuse_synthetic, for synthetic.
flowsteer::servo::FlowMethod flow_method_option(const std::string& option, const std::string& name,
                                                const std::string& noun, const std::string& known,
                                                bool refuse_synthetic = false) {
  const auto method = flowsteer::servo::parse_flow_method(name);
  if (!method || (refuse_synthetic && *method == flowsteer::servo::FlowMethod::synthetic)) {
    throw CLI::ValidationError(option,
                               "unknown " + noun + " '" + name + "' (known: " + known + ")");
  }
  return *method;
}

flowsteer::servo::SegmentationMethod segmentation_method_option(const std::string& option,
                                                                const std::string& name) {
  const auto method = flowsteer::servo::parse_segmentation_method(name);
  if (!method) {
    throw CLI::ValidationError(option, "unknown method '" + name + "' (known: " +
                                           flowsteer::servo::segmentation_method_names() + ")");
  }
  return *method;
}

// The scenario a command runs: a scenario file, a built-in scenario by name or, where the command
// has --steersuite, a SteerSuite test case; at most one of them, the built-in "room" when none.
flowsteer::sim_camera::WorldSpec load_world(const std::string& command, const std::string& file,
                                            const std::string& name,
                                            const std::string* steersuite = nullptr) {
  const bool has_steersuite = steersuite && !steersuite->empty();
  if (!file.empty() + !name.empty() + has_steersuite > 1) {
    throw CLI::ValidationError(command, std::string("give one of SCENARIO_FILE, --scenario") +
                                            (steersuite ? ", --steersuite" : ""));
  }
  if (!file.empty()) {
    return flowsteer::config::load_scenario(file);
  }
  if (has_steersuite) {
    return flowsteer::config::load_steersuite(*steersuite);
  }
  return flowsteer::config::builtin_scenario(name.empty() ? "room" : name);
}

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

  CLI::App* sim = app.add_subcommand(
      "sim", "Run agents that see a rendered world and steer by its optical flow");
  std::string scenario_file;
  std::string scenario_name;
  std::string steersuite_file;
  std::string out_dir = "flowsteer_out";
  int sim_resolution = 0;
  int steps = 0;
  bool video = false;
  sim->add_option("scenario_file", scenario_file, "scenario YAML (see launch/scenarios/room.yaml)");
  sim->add_option("--scenario", scenario_name,
                  "a built-in scenario (flowsteer scenarios lists them)");
  sim->add_option("--steersuite", steersuite_file, "a SteerSuite test case (XML)");
  sim->add_option("--out", out_dir, "folder for the outputs")->capture_default_str();
  sim->add_option("--resolution", sim_resolution, "every agent's camera: N x N pixels")
      ->check(CLI::Range(8, 4096));
  sim->add_option("--steps", steps, "stop after N control steps")->check(CLI::PositiveNumber);
  sim->add_flag("--video", video, "an MP4 per agent: its view, the flow and the features");
  std::string flow_method;
  std::string segmentation_method;
  sim->add_option("--flow", flow_method,
                  "every agent's flow: " + flowsteer::servo::flow_method_names());
  sim->add_option("--segmentation", segmentation_method,
                  "every agent's segmentation: " + flowsteer::servo::segmentation_method_names());

  CLI::App* compare = app.add_subcommand(
      "compare",
      "Run one scenario once per steering model and write the runs side by side: top views, a "
      "table of collisions, goals, path lengths and clearances, turn-rate histograms");
  std::string compare_file;
  std::string compare_name;
  std::string compare_out = "flowsteer_compare";
  std::vector<std::string> controllers;
  int compare_resolution = 0;
  int compare_steps = 0;
  compare->add_option("scenario_file", compare_file, "scenario YAML");
  compare->add_option("--scenario", compare_name, "a built-in scenario (flowsteer scenarios)");
  compare
      ->add_option("--controllers", controllers,
                   "comma-separated steering models: " + flowsteer::servo::steering_model_names())
      ->delimiter(',')
      ->required();
  compare->add_option("--out", compare_out, "folder for the outputs")->capture_default_str();
  compare->add_option("--resolution", compare_resolution, "every agent's camera: N x N pixels")
      ->check(CLI::Range(8, 4096));
  compare->add_option("--steps", compare_steps, "stop each run after N control steps")
      ->check(CLI::PositiveNumber);

  app.add_subcommand("scenarios", "List the built-in scenarios");

  CLI::App* eval = app.add_subcommand("eval", "Measure parts of the pipeline against the truth");
  eval->require_subcommand(1);
  CLI::App* eval_flow = eval->add_subcommand(
      "flow", "Each optical-flow estimator against the renderer's flow and the exact features");
  std::string eval_scenario = "flow_targets";
  std::vector<int> eval_resolutions{256};
  int eval_frames = 40;
  std::vector<std::string> eval_methods;
  std::string eval_segmentation = "semantic";
  std::string eval_out = "flowsteer_eval";
  eval_flow->add_option("--scenario", eval_scenario, "a built-in scenario or a scenario file")
      ->capture_default_str();
  eval_flow->add_option("--resolution", eval_resolutions, "N x N pixels; repeat for several")
      ->check(CLI::Range(16, 2048))
      ->capture_default_str();
  eval_flow->add_option("--frames", eval_frames, "frames rendered per resolution")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  eval_flow->add_option(
      "--method", eval_methods,
      "an estimator (default: all); repeat for several: " + flowsteer::servo::flow_method_names());
  eval_flow
      ->add_option("--segmentation", eval_segmentation,
                   "how objects are found: " + flowsteer::servo::segmentation_method_names() +
                       " (semantic measures the flow alone)")
      ->capture_default_str();
  eval_flow->add_option("--out", eval_out, "folder for flow_eval.csv and flow_eval.txt")
      ->capture_default_str();

  CLI::App* eval_robustness = eval->add_subcommand(
      "robustness",
      "Run a scenario at several camera resolutions, with each flow and segmentation given, and "
      "count the runs with no collision and every goal reached");
  std::string robustness_file;
  std::string robustness_name;
  std::vector<int> robustness_resolutions;
  std::vector<std::string> robustness_flows;
  std::vector<std::string> robustness_segmentations;
  int robustness_steps = 0;
  std::string robustness_out = "flowsteer_robustness";
  eval_robustness->add_option("scenario_file", robustness_file, "scenario YAML");
  eval_robustness->add_option("--scenario", robustness_name,
                              "a built-in scenario (flowsteer scenarios)");
  eval_robustness->add_option("--resolution", robustness_resolutions,
                              "N x N pixels; repeat for several (default: the scenario's own "
                              "and 8, 16, 24, 32 pixels either side)");
  eval_robustness->add_option("--flow", robustness_flows,
                              "every agent's flow (default: the scenario's); repeat for several: " +
                                  flowsteer::servo::flow_method_names());
  eval_robustness->add_option("--segmentation", robustness_segmentations,
                              "every agent's segmentation (default: the scenario's); repeat for "
                              "several: " +
                                  flowsteer::servo::segmentation_method_names());
  eval_robustness->add_option("--steps", robustness_steps, "stop each run after N control steps")
      ->check(CLI::PositiveNumber);
  eval_robustness
      ->add_option("--out", robustness_out, "folder for robustness.csv and robustness.txt")
      ->capture_default_str();

  CLI::App* calibrate =
      app.add_subcommand("calibrate", "Measure a camera's intrinsics and its mount on the robot");
  calibrate->require_subcommand(1);
  const std::string board_help =
      "calibration target: chessboard:COLSxROWS:SQUARE_M (inner corners) or "
      "charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT (squares, e.g. DICT_4X4_50)";
  const std::string model_help = "lens model: pinhole (plumb_bob), rational or fisheye";
  flowsteer::launch::IntrinsicsCommand intrinsics_command;
  CLI::App* intrinsics = calibrate->add_subcommand(
      "intrinsics", "Calibrate from images of a board; write a ROS camera_info YAML");
  intrinsics->add_option("--images", intrinsics_command.images, "images, a quoted glob")
      ->required();
  intrinsics->add_option("--board", intrinsics_command.board, board_help)->required();
  intrinsics->add_option("--model", intrinsics_command.model, model_help)->capture_default_str();
  intrinsics->add_option("--out", intrinsics_command.out, "camera_info file to write")
      ->capture_default_str();
  intrinsics->add_option("--camera-name", intrinsics_command.camera_name, "camera_name field")
      ->capture_default_str();
  intrinsics->add_option("--min-views", intrinsics_command.min_views, "fewest usable views")
      ->check(CLI::Range(3, 1000))
      ->capture_default_str();

  flowsteer::launch::CaptureCommand capture_command;
  std::string device;
  CLI::App* capture = calibrate->add_subcommand(
      "capture",
      "Grab views of a board from a camera, keep the ones that add coverage or a new pose, "
      "calibrate and write the views, camera_info.yaml and report.txt into a folder");
  capture->add_option("--device", device, "camera device, e.g. /dev/video0")->required();
  capture->add_option("--board", capture_command.board, board_help)->required();
  capture->add_option("--out", capture_command.out_dir, "folder for the outputs")
      ->capture_default_str();
  capture->add_option("--model", capture_command.model, model_help)->capture_default_str();
  capture->add_option("--views", capture_command.capture.views, "views to collect")
      ->check(CLI::Range(3, 200))
      ->capture_default_str();
  capture
      ->add_option("--max-frames", capture_command.capture.max_frames,
                   "give up after this many frames")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  capture->add_option("--camera-name", capture_command.camera_name, "camera_name field")
      ->capture_default_str();

  flowsteer::launch::MountCommand mount_command;
  CLI::App* mount = calibrate->add_subcommand(
      "mount",
      "Camera height, pitch and roll from one image of a board lying flat on the floor; write "
      "the camera mount file");
  mount->add_option("--intrinsics", mount_command.intrinsics, "the camera's camera_info YAML")
      ->required();
  mount->add_option("--image", mount_command.image, "image of the board on the floor")->required();
  mount->add_option("--board", mount_command.board, board_help)->required();
  mount->add_option("--out", mount_command.out, "camera mount file to write")
      ->capture_default_str();
  mount
      ->add_option("--board-thickness", mount_command.board_thickness_m,
                   "metres from the floor to the board's printed surface")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();

  flowsteer::launch::RunCommand run_command;
  double run_goal_bearing_deg = 0.0;
  double run_goal_distance_m = 0.0;
  CLI::App* run = app.add_subcommand(
      "run",
      "The robot's loop from a launch file: camera -> flow -> features -> controller -> drive "
      "(launch/launch_files/README.md); Ctrl-C stops the base and ends the run");
  run->add_option("LAUNCH", run_command.launch_file, "robot launch file (YAML)")->required();
  CLI::Option* run_bearing = run->add_option(
      "--goal-bearing", run_goal_bearing_deg,
      "goal bearing from the start heading, degrees, positive to the right (overrides goal:)");
  CLI::Option* run_distance =
      run->add_option("--goal-distance", run_goal_distance_m, "goal distance, metres");
  run->add_option("--log", run_command.log_file,
                  "also write the events and one line per frame (status, objects, command) here");

  flowsteer::launch::ReplayCommand replay_command;
  double replay_hfov_deg = 0.0;
  double replay_goal_bearing_deg = 0.0;
  std::string replay_flow = "dis_medium";
  CLI::App* replay = app.add_subcommand(
      "replay",
      "The pipeline on a recorded video without a drive: features.csv, commands.csv and "
      "overlay.mp4 in a folder");
  replay->add_option("VIDEO", replay_command.video, "video file or image pattern")->required();
  replay->add_option("--out", replay_command.out_dir, "folder for the outputs")
      ->capture_default_str();
  CLI::Option* replay_hfov =
      replay->add_option("--hfov-deg", replay_hfov_deg, "horizontal field of view (default 60)");
  CLI::Option* replay_info =
      replay->add_option("--camera-info", replay_command.camera_info, "ROS camera_info YAML");
  replay_hfov->excludes(replay_info);
  replay->add_option("--flow", replay_flow, "numerical flow method")->capture_default_str();
  CLI::Option* replay_bearing = replay->add_option("--goal-bearing", replay_goal_bearing_deg,
                                                   "goal bearing, degrees, positive to the right");
  replay
      ->add_option("--speed", replay_command.speed_mps,
                   "assumed camera speed, m/s (no odometry in a recording); 0 skips the "
                   "flat-ground test")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  try {
    if (app.got_subcommand("scenarios")) {
      for (const auto& s : flowsteer::config::builtin_scenarios()) {
        std::cout << s.name << std::string(s.name.size() < 18 ? 18 - s.name.size() : 1, ' ')
                  << s.description << "\n";
      }
    }
    if (*run) {
      if (*run_bearing) {
        run_command.goal_bearing_deg = run_goal_bearing_deg;
      }
      if (*run_distance) {
        run_command.goal_distance_m = run_goal_distance_m;
      }
      install_stop_handlers();
      const auto result =
          flowsteer::launch::run_robot_command(run_command, g_stop_requested, std::cerr);
      if (result.reason == flowsteer::launch::StopReason::camera_timeout) {
        // The base was stopped; the run still failed at what it was asked to do.
        return 3;
      }
    }
    if (*replay) {
      // run_replay_command refuses synthetic flow, saying why.
      replay_command.flow = flow_method_option("--flow", replay_flow, "method",
                                               flowsteer::config::numerical_flow_method_names());
      if (*replay_hfov) {
        replay_command.hfov_deg = replay_hfov_deg;
      }
      if (*replay_bearing) {
        replay_command.goal_bearing_deg = replay_goal_bearing_deg;
      }
      const auto summary = flowsteer::launch::run_replay_command(replay_command, std::cerr);
      std::cout << "replay " << replay_command.video << " -> " << replay_command.out_dir << ": "
                << summary.frames << " frames (" << summary.blind_frames << " without flow), "
                << summary.object_rows << " object rows, " << summary.mean_step_ms
                << " ms per frame (perception and controller)\n";
    }
    if (*intrinsics) {
      flowsteer::launch::run_calibrate_intrinsics(intrinsics_command, std::cout, std::cerr);
    }
    if (*capture) {
      capture_command.min_views =
          std::min(capture_command.min_views, capture_command.capture.views);
      const auto source = flowsteer::launch::open_camera(device);
      flowsteer::launch::run_calibrate_capture(capture_command, *source, std::cout, std::cerr);
    }
    if (*mount) {
      flowsteer::launch::run_calibrate_mount(mount_command, std::cout, std::cerr);
    }
    if (*sim) {
      const flowsteer::sim_camera::WorldSpec world =
          load_world("sim", scenario_file, scenario_name, &steersuite_file);
      flowsteer::eval::SimOptions options;
      options.out_dir = out_dir;
      if (sim_resolution > 0) {
        options.resolution = sim_resolution;
      }
      if (steps > 0) {
        options.steps = steps;
      }
      if (!flow_method.empty()) {
        options.flow = flow_method_option("--flow", flow_method, "method",
                                          flowsteer::servo::flow_method_names());
      }
      if (!segmentation_method.empty()) {
        options.segmentation = segmentation_method_option("--segmentation", segmentation_method);
      }
      options.video = video;
      options.progress_bar = isatty(STDERR_FILENO) != 0;
      std::cerr << "flowsteer sim: " << world.name << " (" << world.agents.size() << " agents) -> "
                << out_dir << "\n";
      const auto result = flowsteer::eval::run_simulation(world, options, std::cerr);
      std::cout << "scenario " << result.scenario << ": " << result.steps << " steps, "
                << result.duration_s << " s simulated, " << result.collisions.size()
                << " collisions\n";
      for (const auto& a : result.agents) {
        std::cout << "  " << a.name << ": "
                  << (a.reached_goal
                          ? "reached its goal in " + std::to_string(a.time_to_goal_s) + " s"
                      : a.final_distance_to_leader_m >= 0.0
                          ? "ended " + std::to_string(a.final_distance_to_leader_m) +
                                " m from its leader"
                          : std::string("did not reach its goal"))
                  << ", path " << a.path_length_m << " m, min clearance " << a.min_clearance_m
                  << " m, " << a.collisions << " collisions\n";
      }
      for (const auto& c : result.collisions) {
        std::cout << "  collision at t = " << c.time_s << " s: " << result.agents[c.agent].name
                  << " with " << c.with << " at (" << c.position_m.x() << ", " << c.position_m.y()
                  << ")\n";
      }
      const auto& t = result.per_agent_step_ms;
      std::cout << "per agent step: " << t.total << " ms (render " << t.render << ", flow "
                << t.flow << ", segment " << t.segment << ", features " << t.features
                << ", control " << t.control << ")\n";
    }
    if (*eval_flow) {
      flowsteer::eval::FlowEvalOptions options;
      options.resolutions = eval_resolutions;
      options.frames = eval_frames;
      for (const std::string& name : eval_methods) {
        options.methods.push_back(flow_method_option(
            "--method", name, "estimator",
            flowsteer::servo::flow_method_names() + "; synthetic is the truth", true));
      }
      options.segmentation = segmentation_method_option("--segmentation", eval_segmentation);
      // --scenario takes a file name (it has a dot) or a built-in scenario's name.
      const bool is_file = eval_scenario.find('.') != std::string::npos;
      const flowsteer::sim_camera::WorldSpec world =
          load_world("eval flow", is_file ? eval_scenario : "", is_file ? "" : eval_scenario);
      const auto rows = flowsteer::eval::evaluate_flow(world, options, std::cerr);
      flowsteer::eval::print_flow_table(rows, std::cout);
      flowsteer::eval::write_flow_evaluation(rows, eval_out);
    }
    if (*eval_robustness) {
      const flowsteer::sim_camera::WorldSpec world =
          load_world("eval robustness", robustness_file, robustness_name);
      flowsteer::eval::RobustnessOptions options;
      options.resolutions = robustness_resolutions;
      for (const std::string& name : robustness_flows) {
        options.flows.push_back(
            flow_method_option("--flow", name, "method", flowsteer::servo::flow_method_names()));
      }
      for (const std::string& name : robustness_segmentations) {
        options.segmentations.push_back(segmentation_method_option("--segmentation", name));
      }
      if (robustness_steps > 0) {
        options.steps = robustness_steps;
      }
      options.out_dir = robustness_out;
      const auto runs = flowsteer::eval::evaluate_robustness(world, options, std::cerr);
      flowsteer::eval::print_robustness_table(runs, std::cout);
    }
    if (*compare) {
      const flowsteer::sim_camera::WorldSpec world =
          load_world("compare", compare_file, compare_name);
      flowsteer::eval::CompareOptions options;
      options.controllers = flowsteer::eval::parse_controllers(controllers);
      options.out_dir = compare_out;
      if (compare_resolution > 0) {
        options.resolution = compare_resolution;
      }
      if (compare_steps > 0) {
        options.steps = compare_steps;
      }
      const auto result = flowsteer::eval::run_compare(world, options, std::cerr);
      std::cout << "scenario " << result.scenario << " -> " << compare_out << "\n";
      flowsteer::eval::print_compare_table(flowsteer::eval::compare_table(result), std::cout);
    }
    if (*demo) {
      DemoScene scene = scene_file.empty() ? flowsteer::config::default_demo_scene()
                                           : flowsteer::config::load_demo_scene(scene_file);
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
            flowsteer::base::CameraIntrinsics::from_horizontal_fov(resolution, resolution, hfov);
      }
      flowsteer::launch::run_demo(scene, std::cout);
    }
  } catch (const CLI::ValidationError& e) {
    std::cerr << "flowsteer: " << e.what() << "\n";
    return 2;
  } catch (const flowsteer::base::ConfigError& e) {
    std::cerr << "flowsteer: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "flowsteer: error: " << e.what() << "\n";
    return 1;
  }
  return EXIT_SUCCESS;
}
