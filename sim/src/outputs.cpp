#include "flowsteer/sim/outputs.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowsteer/base/output_files.hpp"
#include "flowsteer/pipeline/overlay.hpp"

namespace flowsteer::sim {

namespace {

constexpr int kCaptionFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kCaptionScale = 0.55;
constexpr int kCaptionMargin = 8;  // px, left of the top view's caption and at least as much right

cv::Scalar agent_color(std::size_t i) {
  static const cv::Scalar palette[] = {{200, 60, 30},  {40, 160, 40},  {30, 60, 220},
                                       {180, 40, 180}, {20, 170, 200}, {120, 90, 20},
                                       {90, 90, 90},   {60, 200, 140}};
  return palette[i % std::size(palette)];
}

namespace fox = recording::foxglove;

fox::Color scene_color(const cv::Scalar& bgr) {
  return {bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, 1.0};
}

// A solid standing on the ground: its centre half its height up, turned by its yaw.
fox::Solid scene_solid(const sim_camera::Solid& s, const fox::Color& color) {
  fox::Solid out;
  out.pose.position = {s.centre_m.x(), s.centre_m.y(), 0.5 * s.height_m};
  out.pose.orientation = recording::ros2::Quaternion::from_yaw(s.yaw_rad);
  out.size = s.shape == sim_camera::Solid::Shape::box
                 ? recording::ros2::Vector3{s.size_m.x(), s.size_m.y(), s.height_m}
                 : recording::ros2::Vector3{2.0 * s.radius_m, 2.0 * s.radius_m, s.height_m};
  out.color = color;
  return out;
}

fox::SceneEntity in_world(const char* id) {
  fox::SceneEntity entity;
  entity.id = id;
  entity.frame_id = "world";
  return entity;
}

void add_solid(fox::SceneEntity& entity, const sim_camera::Solid& s, const fox::Color& color) {
  auto& list = s.shape == sim_camera::Solid::Shape::box ? entity.cubes : entity.cylinders;
  list.push_back(scene_solid(s, color));
}

}  // namespace

std::vector<fox::SceneEntity> static_scene_entities(const sim_camera::World& world) {
  const sim_camera::WorldSpec& spec = world.spec();
  std::vector<fox::SceneEntity> entities = {in_world("obstacles"), in_world("goals")};
  fox::SceneEntity& obstacles = entities[0];
  for (const sim_camera::Solid& o : spec.obstacles) {
    add_solid(obstacles, o, {0.6, 0.6, 0.6, 1.0});
  }
  fox::SceneEntity& goals = entities[1];
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    for (const Eigen::Vector2d& g : spec.agents[i].goals) {
      fox::Color color = scene_color(agent_color(i));
      color.a = 0.35;
      const double d = 2.0 * spec.agents[i].goal_radius_m;
      goals.cylinders.push_back({{{g.x(), g.y(), 0.01}, {}}, {d, d, 0.02}, color});
    }
  }
  return entities;
}

std::vector<fox::SceneEntity> moving_scene_entities(const sim_camera::World& world) {
  const sim_camera::WorldSpec& spec = world.spec();
  std::vector<fox::SceneEntity> entities = {in_world("agents"), in_world("moving")};
  fox::SceneEntity& agents = entities[0];
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    if (!world.present(i)) {
      continue;
    }
    const sim_camera::AgentSpec& a = spec.agents[i];
    const sim_camera::AgentState& s = world.agents()[i];
    sim_camera::Solid body;
    body.shape = sim_camera::Solid::Shape::cylinder;
    body.centre_m = s.position_m;
    body.radius_m = a.radius_m;
    body.height_m = a.height_m;
    add_solid(agents, body, scene_color(agent_color(i)));
    agents.texts.push_back({{{s.position_m.x(), s.position_m.y(), a.height_m + 0.2}, {}},
                            a.name,
                            14.0,
                            scene_color(agent_color(i))});
  }
  fox::SceneEntity& moving = entities[1];
  for (std::size_t k = 0; k < spec.moving.size(); ++k) {
    add_solid(moving, world.moving_now(k), {0.43, 0.43, 0.43, 1.0});
  }
  return entities;
}

void write_image(const std::filesystem::path& path, const cv::Mat& image) {
  std::vector<std::uint8_t> encoded;
  bool ok = false;
  try {
    ok = cv::imencode(path.extension().string(), image, encoded);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot write " + path.string() + ": " + e.what());
  }
  if (!ok) {
    throw std::runtime_error("cannot write " + path.string() + ": cannot encode the image as " +
                             path.extension().string());
  }
  base::write_bytes(path, encoded.data(), encoded.size());
}

void write_summary_json(const std::filesystem::path& path, const SimResult& result) {
  std::ostringstream out;
  out << "{\n  \"scenario\": " << base::json_string(result.scenario)
      << ",\n  \"arrival\": " << base::json_string(std::string(to_string(result.arrival)))
      << ",\n  \"steps\": " << result.steps
      << ",\n  \"duration_s\": " << base::json_number(result.duration_s) << ",\n  \"agents\": [\n";
  for (std::size_t i = 0; i < result.agents.size(); ++i) {
    const AgentResult& a = result.agents[i];
    out << "    {\"name\": " << base::json_string(a.name)
        << ", \"reached_goal\": " << (a.reached_goal ? "true" : "false") << ", \"time_to_goal_s\": "
        << (a.reached_goal ? base::json_number(a.time_to_goal_s) : "null")
        << ", \"path_length_m\": " << base::json_number(a.path_length_m)
        << ", \"min_clearance_m\": " << base::json_number(a.min_clearance_m)
        << ", \"collisions\": " << a.collisions
        << ", \"spinning_s\": " << base::json_number(a.spinning_s);
    if (a.final_distance_to_leader_m >= 0.0) {
      out << ", \"final_distance_to_leader_m\": "
          << base::json_number(a.final_distance_to_leader_m);
    }
    out << "}" << (i + 1 < result.agents.size() ? "," : "") << "\n";
  }
  const pipeline::StageTimes& t = result.per_agent_step_ms;
  out << "  ],\n  \"collisions_total\": " << result.collisions.size()
      << ",\n  \"spinning_s_total\": " << base::json_number(summarize(result).spinning_s)
      << ",\n  \"per_agent_step_ms\": {\"render\": " << base::json_number(t.render)
      << ", \"flow\": " << base::json_number(t.flow)
      << ", \"segment\": " << base::json_number(t.segment)
      << ", \"features\": " << base::json_number(t.features)
      << ", \"control\": " << base::json_number(t.control)
      << ", \"total\": " << base::json_number(t.total) << "},\n  \"threads\": " << result.threads
      << ",\n  \"world_steps_per_s\": " << base::json_number(result.world_steps_per_s) << "\n}\n";
  base::write_text(path, out.str());
}

cv::Mat draw_overlay(const SimulatedAgent& agent) {
  const pipeline::Brain& brain = agent.brain();
  return pipeline::draw_overlay(agent.frame().image, brain.flow(), brain.objects(),
                                agent.intrinsics(), brain.goal_bearing_rad());
}

cv::Mat draw_topview(const sim_camera::World& world,
                     const std::vector<std::vector<Eigen::Vector2d>>& paths,
                     const std::vector<sim_camera::Collision>& collisions) {
  const sim_camera::WorldSpec& spec = world.spec();
  Eigen::AlignedBox2d bounds;
  for (const auto& path : paths) {
    for (const auto& p : path) {
      bounds.extend(p);
    }
  }
  for (const auto& a : spec.agents) {
    bounds.extend(a.start_m);
    for (const auto& g : a.goals) {
      bounds.extend(g);
    }
  }
  for (const auto& o : spec.obstacles) {
    if (o.shape == sim_camera::Solid::Shape::box) {
      for (const Eigen::Vector2d& corner : sim_camera::box_corners(o)) {
        bounds.extend(corner);
      }
    } else {
      bounds.extend(o.centre_m - Eigen::Vector2d(o.radius_m, o.radius_m));
      bounds.extend(o.centre_m + Eigen::Vector2d(o.radius_m, o.radius_m));
    }
  }
  const Eigen::Vector2d margin(1.5, 1.5);
  const Eigen::Vector2d lo = bounds.min() - margin;
  const Eigen::Vector2d extent = bounds.max() + margin - lo;
  const double scale = 900.0 / std::max(extent.x(), extent.y());
  char caption[200];
  std::snprintf(caption, sizeof caption, "%s  t = %.1f s  collisions: %zu  (1 m = %.0f px)%s",
                spec.name.c_str(), world.time_s(), collisions.size(), scale,
                spec.arrival == sim_camera::Arrival::leave ? "  ring: left on arrival" : "");
  const int caption_width = cv::getTextSize(caption, kCaptionFont, kCaptionScale, 1, nullptr).width;
  // A narrow world (a corridor) is centred in an image wide enough for the caption.
  const int world_width = static_cast<int>(extent.x() * scale);
  const cv::Size size(std::max(world_width, caption_width + 2 * kCaptionMargin),
                      static_cast<int>(extent.y() * scale) + 30);
  const int left = (size.width - world_width) / 2;
  cv::Mat image(size, CV_8UC3, cv::Scalar(250, 250, 250));
  // World y points up in the picture.
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(left + static_cast<int>((p.x() - lo.x()) * scale),
                     static_cast<int>(size.height - 30 - (p.y() - lo.y()) * scale));
  };
  auto draw_solid = [&](const sim_camera::Solid& s, const cv::Scalar& color, int thickness) {
    if (s.shape == sim_camera::Solid::Shape::cylinder) {
      cv::circle(image, px(s.centre_m), static_cast<int>(s.radius_m * scale), color, thickness,
                 cv::LINE_AA);
      return;
    }
    std::vector<cv::Point> corners;
    for (const Eigen::Vector2d& corner : sim_camera::box_corners(s)) {
      corners.push_back(px(corner));
    }
    if (thickness == cv::FILLED) {
      cv::fillConvexPoly(image, corners, color, cv::LINE_AA);
    } else {
      cv::polylines(image, corners, true, color, thickness, cv::LINE_AA);
    }
  };
  for (const auto& o : spec.obstacles) {
    draw_solid(o, cv::Scalar(150, 150, 150), cv::FILLED);
  }
  for (std::size_t k = 0; k < spec.moving.size(); ++k) {
    const auto& m = spec.moving[k];
    for (std::size_t w = 1; w < m.waypoints.size(); ++w) {
      cv::line(image, px(m.waypoints[w - 1]), px(m.waypoints[w]), cv::Scalar(200, 200, 200), 1);
    }
    draw_solid(world.moving_now(k), cv::Scalar(110, 110, 110), 2);
  }
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const cv::Scalar color = agent_color(i);
    const auto& path = paths[i];
    for (std::size_t k = 1; k < path.size(); ++k) {
      cv::line(image, px(path[k - 1]), px(path[k]), color, 2, cv::LINE_AA);
    }
    const auto& agent = spec.agents[i];
    cv::circle(image, px(agent.start_m), static_cast<int>(agent.radius_m * scale), color, 1,
               cv::LINE_AA);
    if (!path.empty()) {
      // Filled where the agent ended in the world, a thick ring where it left it.
      cv::circle(image, px(path.back()), static_cast<int>(agent.radius_m * scale), color,
                 world.present(i) ? cv::FILLED : 3, cv::LINE_AA);
    }
    for (const auto& g : agent.goals) {
      cv::drawMarker(image, px(g), color, cv::MARKER_CROSS, 14, 2);
    }
  }
  for (const auto& c : collisions) {
    cv::drawMarker(image, px(c.position_m), cv::Scalar(0, 0, 255), cv::MARKER_TILTED_CROSS, 18, 3);
  }
  cv::putText(image, caption, {kCaptionMargin, size.height - 10}, kCaptionFont, kCaptionScale,
              cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  return image;
}

}  // namespace flowsteer::sim
