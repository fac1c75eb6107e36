// A simulated agent's depth source: with the ground's depth only, the renderer's exact flow is
// seen as a camera sees it (no depth per pixel, depths where objects stand on the ground, no flow
// in the sky), so the law's depth-free path can be measured apart from numerical flow's noise.

#include <cmath>
#include <optional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/sim/simulated_agent.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace {

using namespace flowsteer;

// Walking at 1 m/s towards a wall under an open sky, its face (it is 0.2 m thick) 3.9 m ahead.
sim_camera::WorldSpec wall_ahead(servo::DepthSource depth, servo::SegmentationMethod segmentation) {
  const std::string text =
      "step_s: 0.05\nduration_s: 1\n"
      "camera: {resolution: 128, hfov_deg: 120, height_m: 1.6}\n"
      "obstacles:\n"
      "  - {shape: wall, from: [4, -20], to: [4, 20], height_m: 2.5}\n"
      "agents:\n"
      "  - {start: [0, 0], heading_deg: 0, speed_mps: 1, goal: [10, 0]}\n";
  sim_camera::WorldSpec spec = config::parse_scenario(text, "wall_ahead.yaml");
  spec.agents[0].perception.depth = depth;
  spec.agents[0].perception.segmentation = segmentation;
  return spec;
}

// The wall as the agent's perception describes it after a few frames.
struct Seen {
  servo::ObjectFeatures wall;
  servo::Segmentation segmentation;
};

Seen look(servo::DepthSource depth, servo::SegmentationMethod segmentation) {
  const sim_camera::World world(wall_ahead(depth, segmentation));
  const auto renderer = sim_camera::Renderer::create();
  sim::SimulatedAgent agent(world, 0);
  pipeline::StageTimes times;
  for (int frame = 0; frame < 3; ++frame) {
    agent.step(*renderer, times);
  }
  Seen seen;
  seen.segmentation = agent.brain().segmentation();
  for (const servo::ObjectFeatures& object : agent.brain().objects()) {
    if (object.pixel_count > seen.wall.pixel_count) {
      seen.wall = object;
    }
  }
  return seen;
}

TEST(DepthSource, TheRenderersDepthIsAtEveryPixel) {
  const Seen seen = look(servo::DepthSource::renderer, servo::SegmentationMethod::semantic);
  ASSERT_TRUE(seen.wall.depth_m);
  EXPECT_NEAR(*seen.wall.depth_m, 3.9, 0.01);
}

TEST(DepthSource, TheGroundsDepthIsWhereTheWallStandsOnIt) {
  const Seen seen = look(servo::DepthSource::ground, servo::SegmentationMethod::semantic);
  ASSERT_GT(seen.wall.pixel_count, 0);
  EXPECT_FALSE(seen.wall.depth_m) << "no depth per pixel: no mean depth";
  ASSERT_TRUE(seen.wall.nearest_depth_m);
  // One row of a 128² view with a 120° field of view is 0.27 m of depth at the wall's foot.
  EXPECT_NEAR(*seen.wall.nearest_depth_m, 3.9, 0.3);
}

// The sky has no depth; without the renderer's depth it has no flow either, as a camera's
// untextured sky, so flow segmentation leaves it out.
TEST(DepthSource, WithTheGroundsDepthTheSkyIsInNoRegion) {
  const Seen seen = look(servo::DepthSource::ground, servo::SegmentationMethod::flow_graph_fast);
  const servo::Segmentation& s = seen.segmentation;
  ASSERT_EQ(s.labels.size(), static_cast<std::size_t>(s.width * s.height));
  // The top row looks 60° up, far above the wall (0.9 m above the eye, 13° up).
  for (int col = 0; col < s.width; ++col) {
    EXPECT_EQ(s.labels[static_cast<std::size_t>(col)], servo::Segmentation::kNoRegion)
        << "column " << col;
  }
}

// A neighbour starting 0.2 m beside the agent, surface to surface, drifting into its path: its
// feet are below a level camera's view (the ground is seen from 0.43 m on), so only the depth
// bound at the image's lower edge gives it a place. Without that bound they walk into each other
// (clearance −0.47 m); with the renderer's depth they pass.
TEST(DepthSource, WithTheGroundsDepthANeighbourWhoseFeetAreBelowTheImageIsAvoided) {
  const std::string text =
      "step_s: 0.05\nduration_s: 12\n"
      "camera: {resolution: 128, hfov_deg: 150, height_m: 1.6}\n"
      "perception: {depth: ground}\n"
      "agents:\n"
      "  - {start: [0, 0], heading_deg: 0, speed_mps: 1, goal: [10, 0]}\n"
      "  - {start: [0.2, 0.7], heading_deg: -10, speed_mps: 1, goal: [10, -3]}\n";
  sim::SimOptions options;
  options.write_outputs = false;
  std::ostringstream log;
  const sim::SimResult result =
      sim::run_simulation(config::parse_scenario(text, "beside.yaml"), options, log);
  EXPECT_EQ(result.collisions.size(), 0U);
  for (const sim::AgentResult& a : result.agents) {
    EXPECT_TRUE(a.reached_goal) << a.name;
    EXPECT_GT(a.min_clearance_m, 0.0) << a.name;
  }
}

}  // namespace
