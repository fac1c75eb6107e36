#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/recording/foxglove_messages.hpp"
#include "flowsteer/sim/simulated_agent.hpp"
#include "flowsteer/sim/simulation.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::sim {

// What a run writes besides its tables (base/output_files.hpp): summary.json, images, the
// agents' overlays and the top view.

void write_summary_json(const std::filesystem::path& path, const SimResult& result);

// Writes `image` to `path` in the format its extension names, or throws std::runtime_error
// naming the file.
void write_image(const std::filesystem::path& path, const cv::Mat& image);

// An agent's view beside its colour-coded derotated flow, with its features drawn
// (pipeline::draw_overlay).
cv::Mat draw_overlay(const SimulatedAgent& agent);

// The world from above (CGF Fig. 5): obstacles, paths coloured per agent with time marks at
// the same moments on every path, goals, collisions; metre ticks along the left and bottom
// edges, then a legend of the agents' colours, a scale bar and what the time marks mean, and a
// caption (scenario, time, collisions, pixels per metre). paths[i][k] is where agent i was at
// k × the world's step_s.
// Where agents are given, each one's closest approach (AgentResult::closest_position_m) is a
// diamond in its colour, and the run's closest is labelled with its clearance and time.
cv::Mat draw_topview(const sim_camera::World& world,
                     const std::vector<std::vector<Eigen::Vector2d>>& paths,
                     const std::vector<sim_camera::Collision>& collisions,
                     std::span<const AgentResult> agents = {});

// Agent i's colour (report::agent_color) as OpenCV draws it (BGR).
cv::Scalar agent_color(std::size_t agent);

// The interval between the top view's numbered time marks for a run of duration_s: 4 to 10
// of them.
double time_mark_interval_s(double duration_s);

// The world as Foxglove draws it in 3D: what stands still (the recording's /world/static: the
// obstacles and the goals), and what moves (its /world: the agents present now with their
// names, in the top view's colours, and the moving obstacles where they are now).
std::vector<recording::foxglove::SceneEntity> static_scene_entities(const sim_camera::World& world);
std::vector<recording::foxglove::SceneEntity> moving_scene_entities(const sim_camera::World& world);

}  // namespace flowsteer::sim
