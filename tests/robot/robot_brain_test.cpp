// The robot's brain and its launch-file sections: perception and controller settings are
// checked like the rest of the file; a blind frame brakes and holds the goal heading; and a
// recording of rendered frames gives the same features as the frames themselves.

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/camera_io/replay_source.hpp"
#include "flowsteer/config/robot_launch.hpp"
#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/robot/robot_brain.hpp"
#include "flowsteer/sim/simulated_agent.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/world.hpp"
#include "robot_launch_errors.hpp"

namespace {

namespace fs = std::filesystem;
using namespace flowsteer;

const char* kCamera = "camera:\n  type: replay\n  replay: {path: run.mp4}\n";
const char* kDrive =
    "drive:\n  type: sim\n  loop_rate_hz: 50\n  geometry: {wheel_separation_m: 0.4, "
    "wheel_radius_m: 0.05}\n";

using robot::test_support::error_of;

TEST(RobotLaunchSections, PerceptionAndControllerAreRead) {
  const config::RobotLaunch l = config::parse_robot_launch(
      std::string(kCamera) + kDrive +
          "perception: {flow: dis_medium, segmentation: flow_graph, dark_regions: true, "
          "height_m: 0.3, pitch_deg: 10}\n"
          "controller: {alpha: 2, gamma: 1, delta: 0.5, preferred_speed_mps: 0.4, "
          "robot_width_m: 0.5}\n",
      "ok.yaml", "");
  EXPECT_EQ(l.perception.flow, servo::FlowMethod::dis_medium);
  EXPECT_EQ(l.perception.segmentation, servo::SegmentationMethod::flow_graph);
  EXPECT_TRUE(l.perception.dark_regions);
  ASSERT_TRUE(l.perception.mount);
  EXPECT_DOUBLE_EQ(l.perception.mount->height_m, 0.3);
  EXPECT_NEAR(l.perception.mount->pitch_rad, 10.0 * M_PI / 180.0, 1e-12);
  EXPECT_DOUBLE_EQ(*l.controller.spec.alpha, 2.0);
  EXPECT_DOUBLE_EQ(*l.controller.spec.delta, 0.5);
  EXPECT_TRUE(l.controller.spec.use_depth) << "the ground's depth where objects stand on it";
  EXPECT_DOUBLE_EQ(l.controller.preferred_speed_mps, 0.4);
  EXPECT_DOUBLE_EQ(l.controller.robot_width_m, 0.5);
}

// The law takes the ground's depth where objects stand on it by default; the launch file may
// turn that off, and without a mount there is no ground to take it from.
TEST(RobotLaunchSections, TheGroundsDepthNeedsTheMount) {
  const auto brain_use_depth = [](const std::string& perception, const std::string& controller) {
    const config::RobotLaunch l = config::parse_robot_launch(
        std::string(kCamera) + kDrive + perception + controller, "depth.yaml", "");
    return robot::robot_brain_config(l.perception, l.controller).controller.use_depth;
  };
  const std::string mount = "perception: {flow: dis_fast, height_m: 0.3, pitch_deg: 5}\n";
  EXPECT_TRUE(brain_use_depth(mount, ""));
  EXPECT_FALSE(brain_use_depth(mount, "controller: {use_depth: false}\n"));
  // A recording replayed (no drive) has no mount.
  EXPECT_FALSE(robot::robot_brain_config({}, {}).controller.use_depth);
}

// The obstacle memory is the launch file's choice, off unless it asks; the Brain uses it since a
// robot's perception is flow segmentation with a camera's depths.
TEST(RobotLaunchSections, ObstacleMemoryIsOffUnlessAskedFor) {
  const auto memory = [](const std::string& perception) {
    const config::RobotLaunch l =
        config::parse_robot_launch(std::string(kCamera) + kDrive + perception, "memory.yaml", "");
    EXPECT_EQ(l.perception.obstacle_memory,
              robot::robot_brain_config(l.perception, l.controller).perception.obstacle_memory);
    return l.perception.obstacle_memory;
  };
  EXPECT_FALSE(memory("perception: {flow: dis_fast, height_m: 0.3, pitch_deg: 5}\n"));
  EXPECT_TRUE(
      memory("perception: {flow: dis_fast, height_m: 0.3, pitch_deg: 5, obstacle_memory: true}\n"));
}

TEST(RobotLaunchSections, BadSectionsNameTheLineAndField) {
  const std::string camera(kCamera);
  EXPECT_EQ(error_of(camera + "perception: {segmentation: semantic}\n"),
            "bad.yaml:4:28: perception.segmentation: semantic segmentation needs a simulator's "
            "object ids; a camera needs flow_graph or flow_graph_fast");
  EXPECT_EQ(error_of(camera + "perception: {flow: lucas}\n").substr(0, 38),
            "bad.yaml:4:20: perception.flow: expect");
  EXPECT_EQ(error_of(camera + "controller: {kind: following}\n"),
            "bad.yaml:4:14: controller.kind: unknown key (expected one of: law, alpha, beta, "
            "gamma, delta, braking, anticipation, lambda, max_accel_mps2, max_turn_rate, "
            "max_speed_ratio, use_depth, clearance_margin_m, preferred_speed_mps, robot_width_m)");
  // The shared reader's checks hold here too.
  EXPECT_EQ(error_of(camera + "controller: {gamma: 0.5, delta: 1}\n"),
            "bad.yaml:4:33: controller.delta: must not exceed gamma (MIG 2019: visible "
            "obstacles weigh at least as much)");
  EXPECT_EQ(error_of(camera + "controller: {delta: 0.5}\n"),
            "bad.yaml:4:13: perception.dark_regions: controller.delta > 0 weighs dark regions: "
            "set perception.dark_regions: true");
  EXPECT_EQ(error_of(camera + kDrive),
            "bad.yaml:1:1: perception.mount: missing: with a drive, the flat-ground test needs "
            "the camera mount (mount: FILE, or height_m and pitch_deg)");
  EXPECT_EQ(error_of(camera + "perception: {mount: m.yaml, height_m: 0.3}\n"),
            "bad.yaml:4:21: perception.mount: give a camera mount file or height_m and "
            "pitch_deg, not both");
  // A missing mount file is named with its path.
  EXPECT_NE(error_of(camera + "perception: {mount: no_such_mount.yaml}\n").find("no_such_mount"),
            std::string::npos);
}

camera_io::Frame textured_frame(double t_s, std::uint64_t sequence, int shift_px) {
  cv::Mat texture(120, 200, CV_8UC3);
  cv::theRNG().state = 3;
  cv::randu(texture, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::GaussianBlur(texture, texture, {0, 0}, 1.5);
  camera_io::Frame frame;
  frame.image = texture(cv::Rect(shift_px, 0, 160, 120)).clone();
  frame.timestamp_s = t_s;
  frame.sequence = sequence;
  return frame;
}

// A blind frame (no flow yet, or a single colour) brakes at the controller's limit and turns
// towards the goal only; the switch to blind and back is logged once each.
TEST(RobotBrain, BlindFramesBrakeAndHoldTheGoalHeading) {
  config::ControllerSection controller;
  controller.spec.use_depth = false;
  controller.spec.max_accel_mps2 = 0.7;
  std::ostringstream log;
  robot::RobotBrain brain(base::CameraIntrinsics::from_horizontal_fov(160, 120, 1.0),
                          robot::robot_brain_config({}, controller), log);
  const drivers::BodyVelocity moving{0.4, 0.0};
  const double goal_right_rad = 0.3;

  const camera_io::Frame first = textured_frame(0.0, 0, 0);
  base::Command c = brain.step({first, moving, goal_right_rad, 5.0});
  EXPECT_TRUE(brain.brain().blind());
  EXPECT_DOUBLE_EQ(c.accel_mps2, -0.7);
  EXPECT_GT(c.turn_rate, 0.0);  // towards the goal, on the right
  // Stopped, it stays stopped: no reversing.
  camera_io::Frame again = first;
  again.sequence = 1;
  c = brain.step({again, {0.0, 0.0}, goal_right_rad, 5.0});
  EXPECT_TRUE(brain.brain().blind());  // the same timestamp: no time for motion
  EXPECT_DOUBLE_EQ(c.accel_mps2, 0.0);

  camera_io::Frame grey = textured_frame(0.1, 2, 0);
  grey.image.setTo(cv::Scalar::all(128));
  c = brain.step({grey, moving, -goal_right_rad, 5.0});
  EXPECT_TRUE(brain.brain().blind());
  EXPECT_LT(c.turn_rate, 0.0);
  EXPECT_DOUBLE_EQ(c.accel_mps2, -0.7);

  brain.step({textured_frame(0.2, 3, 2), moving, goal_right_rad, 5.0});
  brain.step({textured_frame(0.3, 4, 4), moving, goal_right_rad, 5.0});
  EXPECT_FALSE(brain.brain().blind());
  const std::string text = log.str();
  EXPECT_NE(text.find("frame 0: blind (no previous frame): braking to a stop, holding the goal "
                      "heading, no avoidance"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("frame 2: blind (single-colour frame)"), std::string::npos) << text;
  EXPECT_NE(text.find("frame 4: flow ok, steering by the features"), std::string::npos) << text;
}

// The pixels of one region.
// Equal, or both NaN (no fit).
bool same(double a, double b) {
  return a == b || (std::isnan(a) && std::isnan(b));
}

// Equal up to the rounding of the times (see below), or both NaN.
bool nearly_same(double a, double b) {
  return same(a, b) || std::abs(a - b) <= 1e-12 * std::abs(b);
}

struct Seen {
  double timestamp_s = 0.0;
  servo::FlowStatus status = servo::FlowStatus::ok;
  std::vector<int> labels;  // the direct render's segmentation
  std::vector<servo::ObjectFeatures> objects;
};

// The check: frames rendered by sim_camera, encoded by OpenCV and replayed through
// ReplaySource give the same features as the rendered frames themselves, through the same
// perception (DIS medium flow, flow-graph segmentation: a recording has no object ids). The
// recording is FFV1 (lossless): with it the container round trip (timestamps from the rate,
// intrinsics from the field of view, BGR frames) is checked exactly, so each frame gives the
// same segmentation and the same objects; a lossy codec would add its own error to the flow.
TEST(ReplayOfRenderedFrames, GivesTheFeaturesOfTheRender) {
  sim_camera::WorldSpec spec = config::builtin_scenario("flow_targets");
  spec.agents[0].camera.width_px = spec.agents[0].camera.height_px = 256;
  spec.agents[0].perception = {};
  sim_camera::World world(spec);
  const auto renderer = sim_camera::Renderer::create();
  // The recorded frames are replayed: the lit image is what a camera would give.
  sim::SimulatedAgent agent(world, 0, sim_camera::RenderChannels::all);

  pipeline::BrainConfig config;
  config.perception.flow = servo::FlowMethod::dis_medium;
  config.perception.segmentation = servo::SegmentationMethod::flow_graph;
  config.perception.use_depth = false;
  config.perception.mount = {spec.agents[0].camera.height_m, spec.agents[0].camera.pitch_rad};
  pipeline::Brain direct(agent.intrinsics(), config);

  const fs::path video = fs::temp_directory_path() /
                         ("flowsteer_replay_of_render_" + std::to_string(::getpid()) + ".avi");
  constexpr int kFrames = 16;
  std::vector<Seen> direct_seen(kFrames);
  std::vector<double> speeds;
  std::vector<cv::Mat> rendered;
  {
    // FFV1 is lossless: the only difference left is the container's round trip.
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('F', 'F', 'V', '1'),
                           1.0 / spec.step_s, {256, 256});
    ASSERT_TRUE(writer.isOpened()) << "OpenCV cannot write FFV1 to " << video;
    std::vector<base::Command> commands(1);
    for (int f = 0; f < kFrames; ++f) {
      pipeline::StageTimes times;
      const servo::ControlOutput& out = agent.step(*renderer, times);
      commands[0] = out.command;
      const sim_camera::AgentState& state = world.agents()[0];
      camera_io::Frame frame = agent.frame();
      frame.sim.reset();  // as a camera would give it
      writer.write(frame.image);
      rendered.push_back(frame.image.clone());
      speeds.push_back(state.speed_mps);
      direct_seen[f].timestamp_s = frame.timestamp_s;
      direct.step({frame, state.speed_mps, 0.0, {}, {}, {}, {}, false});
      direct_seen[f].status = direct.flow_status();
      if (direct_seen[f].status == servo::FlowStatus::ok) {
        direct_seen[f].labels = direct.segmentation().labels;
        direct_seen[f].objects.assign(direct.objects().begin(), direct.objects().end());
      }
      world.step(commands);
    }
  }

  camera_io::ReplayOptions replay_options;
  replay_options.path = video.string();
  replay_options.frame_rate_hz = 1.0 / spec.step_s;
  replay_options.lens.horizontal_fov_rad = spec.agents[0].camera.hfov_rad;
  camera_io::ReplaySource source(replay_options);
  EXPECT_NEAR(source.intrinsics().fx_px, agent.intrinsics().fx_px, 1e-9);
  pipeline::Brain replayed(source.intrinsics(), config);
  camera_io::Frame frame;
  int f = 0;
  int compared = 0;
  while (source.read(frame, 0.0) == camera_io::ReadStatus::ok) {
    ASSERT_LT(f, kFrames);
    ASSERT_EQ(cv::norm(frame.image, rendered[f], cv::NORM_INF), 0.0) << "frame " << f;
    // The decoded frame is the rendered one bit for bit (checked above), at the same time up to
    // rounding (frame / rate against the world's summed steps): the same perception gives the
    // same segmentation and the same features, time to contact up to that rounding.
    SCOPED_TRACE("frame " + std::to_string(f));
    const Seen& seen = direct_seen[f];
    EXPECT_DOUBLE_EQ(frame.timestamp_s, seen.timestamp_s);
    replayed.step({frame, speeds[f], 0.0, {}, {}, {}, {}, false});
    ASSERT_EQ(replayed.flow_status(), seen.status);
    if (seen.status == servo::FlowStatus::ok) {
      EXPECT_EQ(replayed.segmentation().labels, seen.labels);
      ASSERT_EQ(replayed.objects().size(), seen.objects.size());
      for (std::size_t k = 0; k < seen.objects.size(); ++k) {
        const servo::ObjectFeatures& o = replayed.objects()[k];
        const servo::ObjectFeatures& d = seen.objects[k];
        EXPECT_EQ(o.label, d.label);
        EXPECT_EQ(o.pixel_count, d.pixel_count);
        EXPECT_EQ(o.status, d.status);
        EXPECT_TRUE(nearly_same(o.ttc_s, d.ttc_s)) << o.ttc_s << " vs " << d.ttc_s;
        EXPECT_TRUE(same(o.foe.x(), d.foe.x()) && same(o.foe.y(), d.foe.y()))
            << o.foe.transpose() << " vs " << d.foe.transpose();
        EXPECT_EQ(o.centre, d.centre);
        compared += d.status == servo::MotionStatus::approaching ? 1 : 0;
      }
    }
    ++f;
  }
  EXPECT_EQ(f, kFrames);
  EXPECT_GE(compared, 10) << "too few approaching objects to compare";
  fs::remove(video);
}

// One brain: the frames a simulated agent renders, driven through the path `flowsteer sim` takes
// (SimulatedAgent) and through the path `flowsteer run` and `replay` take (RobotBrain, on the
// frames without the renderer's channels, as a camera gives them), give the same command bit for
// bit at every frame, blind frames included, for every model a camera can run. The geometric
// model needs the simulator's geometry, which a robot refuses by name.
struct Recorded {
  camera_io::Frame frame;
  double speed_mps;
  double turn_rate;
  std::optional<double> goal_bearing_rad;
  std::optional<double> goal_distance_m;
  base::Command command;
};

std::vector<Recorded> record_simulated_agent(sim_camera::WorldSpec spec, int frames) {
  sim_camera::World world(spec);
  const auto renderer = sim_camera::Renderer::create();
  // The recorded frames are replayed: the lit image is what a camera would give.
  sim::SimulatedAgent agent(world, 0, sim_camera::RenderChannels::all);
  std::vector<Recorded> recorded;
  std::vector<base::Command> commands(spec.agents.size());
  for (int f = 0; f < frames; ++f) {
    const sim_camera::AgentState state = world.agents()[0];
    pipeline::StageTimes times;
    const servo::ControlOutput& out = agent.step(*renderer, times);
    Recorded r{agent.frame(),
               state.speed_mps,
               state.turn_rate,
               agent.brain().goal_bearing_rad(),
               agent.brain().goal_distance_m(),
               out.command};
    r.frame.image = r.frame.image.clone();
    r.frame.sim.reset();  // as a camera gives it
    recorded.push_back(std::move(r));
    commands[0] = out.command;
    world.step(commands);
  }
  return recorded;
}

class OneBrain : public ::testing::TestWithParam<servo::SteeringModel> {};

TEST_P(OneBrain, SimulatorAndRobotPathsGiveTheSameCommands) {
  sim_camera::WorldSpec spec = config::builtin_scenario("room");
  for (sim_camera::AgentSpec& a : spec.agents) {
    a.camera.width_px = a.camera.height_px = 96;
    a.perception = {servo::FlowMethod::dis_fast, servo::SegmentationMethod::flow_graph_fast};
    a.controller.model = GetParam();
    a.controller.mass_from = servo::MassSource::ground;  // a camera has no object ids
  }
  sim_camera::AgentSpec& walker = spec.agents[0];
  walker.start_speed_mps = 0.8;  // moving while blind: the first frames brake
  const std::vector<Recorded> recorded = record_simulated_agent(spec, 40);

  config::PerceptionSection perception;
  perception.flow = walker.perception.flow;
  perception.segmentation = walker.perception.segmentation;
  perception.mount = base::CameraMount{walker.camera.height_m, walker.camera.pitch_rad};
  config::ControllerSection controller;
  controller.spec = walker.controller;
  controller.robot_width_m = 2.0 * walker.radius_m;
  controller.preferred_speed_mps = walker.preferred_speed_mps;
  std::ostringstream log;
  robot::RobotBrain robot(
      base::CameraIntrinsics::from_horizontal_fov(96, 96, walker.camera.hfov_rad),
      robot::robot_brain_config(perception, controller), log);

  int blind = 0;
  int turning = 0;
  for (std::size_t f = 0; f < recorded.size(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    const Recorded& r = recorded[f];
    const base::Command c =
        robot.step({r.frame, {r.speed_mps, r.turn_rate}, r.goal_bearing_rad, r.goal_distance_m});
    EXPECT_EQ(c.accel_mps2, r.command.accel_mps2);
    EXPECT_EQ(c.turn_rate, r.command.turn_rate);
    blind += robot.brain().blind() ? 1 : 0;
    turning += std::abs(c.turn_rate) > 1e-3 ? 1 : 0;
  }
  EXPECT_GE(blind, 1);
  EXPECT_EQ(recorded.front().command.accel_mps2, -walker.controller.max_accel_mps2);
  EXPECT_GE(turning, 10) << "too few frames that steer to compare";
}

INSTANTIATE_TEST_SUITE_P(CameraModels, OneBrain,
                         ::testing::Values(servo::SteeringModel::vision,
                                           servo::SteeringModel::motion_energy),
                         [](const auto& info) {
                           return std::string(servo::to_string(info.param));
                         });

TEST(OneBrain, TheGeometricModelNeedsTheSimulatorsGeometry) {
  config::ControllerSection controller;
  controller.spec.model = servo::SteeringModel::geometric;
  std::ostringstream log;
  try {
    robot::RobotBrain robot(base::CameraIntrinsics::from_horizontal_fov(64, 64, 1.0),
                            robot::robot_brain_config({}, controller), log);
    FAIL() << "a robot ran the geometric model";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exact geometry"), std::string::npos) << e.what();
  }
}

}  // namespace
