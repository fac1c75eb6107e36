#include "flowsteer/sim_camera/world_geometry.hpp"

#include <cmath>
#include <numbers>

namespace flowsteer::sim_camera {

namespace {

// Sides of the polygon that stands for a circle: its width seen from any side is within
// 1/cos(π/16) − 1 < 2 % of the circle's.
constexpr int kCircleSides = 16;

}  // namespace

std::array<Eigen::Vector2d, 4> box_corners(const Solid& box) {
  const double cy = std::cos(box.yaw_rad);
  const double sy = std::sin(box.yaw_rad);
  const Eigen::Vector2d half = 0.5 * box.size_m;
  std::array<Eigen::Vector2d, 4> corners = {
      Eigen::Vector2d(half.x(), half.y()), Eigen::Vector2d(-half.x(), half.y()),
      Eigen::Vector2d(-half.x(), -half.y()), Eigen::Vector2d(half.x(), -half.y())};
  for (Eigen::Vector2d& corner : corners) {
    const Eigen::Vector2d rotated(cy * corner.x() - sy * corner.y(),
                                  sy * corner.x() + cy * corner.y());
    corner = box.centre_m + rotated;
  }
  return corners;
}

std::span<const servo::GeometricBody> WorldGeometry::bodies_seen_by(const World& world,
                                                                    std::size_t agent) {
  const AgentState& self = world.agents().at(agent);
  const double c = std::cos(self.yaw_rad);
  const double s = std::sin(self.yaw_rad);
  // World to the agent's body frame (x forward, y left).
  auto to_body = [&](const Eigen::Vector2d& world_vector) {
    return Eigen::Vector2d(c * world_vector.x() + s * world_vector.y(),
                           -s * world_vector.x() + c * world_vector.y());
  };
  points_.clear();
  offsets_.clear();
  bodies_.clear();
  auto add_circle = [&](const Eigen::Vector2d& centre, double radius) {
    const double r = radius / std::cos(std::numbers::pi / kCircleSides);
    for (int k = 0; k < kCircleSides; ++k) {
      const double a = 2.0 * std::numbers::pi * k / kCircleSides;
      points_.push_back(
          to_body(centre + r * Eigen::Vector2d(std::cos(a), std::sin(a)) - self.position_m));
    }
  };
  auto add_solid = [&](const Solid& solid) {
    if (solid.shape == Solid::Shape::cylinder) {
      add_circle(solid.centre_m, solid.radius_m);
      return;
    }
    for (const Eigen::Vector2d& corner : box_corners(solid)) {
      points_.push_back(to_body(corner - self.position_m));
    }
  };
  auto add_body = [&](std::int32_t id, double height_m, const Eigen::Vector2d& velocity_world) {
    offsets_.push_back(points_.size());
    bodies_.push_back({id, {}, height_m, to_body(velocity_world)});
  };

  const WorldSpec& spec = world.spec();
  for (std::size_t j = 0; j < spec.agents.size(); ++j) {
    if (j != agent && world.present(j)) {
      add_body(agent_render_id(j), spec.agents[j].height_m, world.agents()[j].velocity_mps());
      add_circle(world.agents()[j].position_m, spec.agents[j].radius_m);
    }
  }
  for (std::size_t k = 0; k < spec.obstacles.size(); ++k) {
    add_body(obstacle_render_id(k), spec.obstacles[k].height_m, Eigen::Vector2d::Zero());
    add_solid(spec.obstacles[k]);
  }
  for (std::size_t k = 0; k < spec.moving.size(); ++k) {
    const Solid body = world.moving_now(k);
    add_body(moving_render_id(k), body.height_m, world.moving()[k].velocity_mps);
    add_solid(body);
  }
  // The points are all in place: only now can the footprints point into them.
  offsets_.push_back(points_.size());
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    bodies_[b].footprint_m = std::span<const Eigen::Vector2d>(points_).subspan(
        offsets_[b], offsets_[b + 1] - offsets_[b]);
  }
  return bodies_;
}

}  // namespace flowsteer::sim_camera
