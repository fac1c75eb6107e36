#include "turn_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include <Eigen/Core>

#include "contact_time.hpp"

namespace flowsteer::servo::detail {

namespace {

// The heading's step between the points where a turn's path is checked.
constexpr double kPathStepRad = 0.05;

// Beyond this bearing a column has no image coordinate worth keeping (tan grows without bound).
constexpr double kMaxBearingRad = 0.49 * std::numbers::pi;

// Image column x after the turn, and the factor by which the depth along the optical axis of a
// point on that column changes (Z = r cos β).
struct Column {
  double x;
  double depth_factor;
};
Column turned_column(double x, double turn_rad) {
  const double bearing = std::atan(x);
  const double after = std::clamp(bearing - turn_rad, -kMaxBearingRad, kMaxBearingRad);
  return {std::tan(after), std::cos(after) / std::cos(bearing)};
}

void scale(std::optional<double>& depth_m, double factor) {
  if (depth_m) {
    *depth_m *= factor;
  }
}

// The object's FOE and τ after the turn: its velocity over the ground (relative velocity plus
// the agent's own) keeps its direction in the world while the frame turns; the agent's own
// stays along the optical axis.
void turn_motion(ObjectFeatures& object, const ObjectFeatures& before, const AgentState& agent,
                 double turn_rad, double centre_depth_factor, const DepthGuess& depth,
                 double static_closing_ratio) {
  if (!before.has_foe() || !std::isfinite(before.ttc_s) || !std::isfinite(before.foe.x())) {
    return;
  }
  const std::optional<Eigen::Vector2d> relative =
      relative_velocity(before, agent, depth, static_closing_ratio);
  if (!relative || !(relative->y() < 0.0)) {
    return;
  }
  const Eigen::Vector2d own{0.0, agent.speed_mps};
  const Eigen::Vector2d after = seen_after_turn(*relative + own, turn_rad) - own;
  if (!(after.y() < 0.0)) {
    object.status = MotionStatus::receding;
    object.ttc_s = std::numeric_limits<double>::infinity();
    return;
  }
  object.foe.x() = after.x() / after.y();
  object.ttc_s = before.ttc_s * centre_depth_factor * relative->y() / after.y();
}

}  // namespace

Eigen::Vector2d seen_after_turn(const Eigen::Vector2d& v, double turn_rad) {
  const double c = std::cos(turn_rad);
  const double s = std::sin(turn_rad);
  return {v.x() * c - v.y() * s, v.y() * c + v.x() * s};
}

void percept_after_turn(const Percept& now, const AgentState& agent, double turn_rad,
                        const DepthGuess& depth, double static_closing_ratio,
                        std::vector<ObjectFeatures>& objects, Percept& out) {
  objects.assign(now.objects.begin(), now.objects.end());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    ObjectFeatures& object = objects[i];
    const Column min = turned_column(object.min_x, turn_rad);
    const Column max = turned_column(object.max_x, turn_rad);
    const Column nearest = turned_column(object.nearest_x, turn_rad);
    const Column centre = turned_column(object.centre.x(), turn_rad);
    object.min_x = min.x;
    object.max_x = max.x;
    object.nearest_x = nearest.x;
    object.centre.x() = centre.x;
    object.width = max.x - min.x;
    scale(object.min_x_depth_m, min.depth_factor);
    scale(object.max_x_depth_m, max.depth_factor);
    scale(object.nearest_depth_m, nearest.depth_factor);
    scale(object.depth_m, centre.depth_factor);
    turn_motion(object, now.objects[i], agent, turn_rad, centre.depth_factor, depth,
                static_closing_ratio);
  }
  out = now;
  out.objects = objects;
  if (out.goal_bearing_rad) {
    *out.goal_bearing_rad -= turn_rad;
  }
}

bool way_onto_goal_is_clear(const Percept& now, const AgentState& agent, double turn_rate,
                            const DepthGuess& depth, double static_closing_ratio,
                            double clearance_m) {
  if (!now.goal_bearing_rad || !now.goal_distance_m || turn_rate == 0.0) {
    return false;
  }
  const double rate = std::abs(turn_rate);
  const double turn_rad = std::abs(*now.goal_bearing_rad);
  const double speed_mps = std::max(0.0, agent.speed_mps);
  const double radius_m = speed_mps / rate;
  const double side = turn_rate > 0.0 ? 1.0 : -1.0;
  const int steps = static_cast<int>(std::ceil(turn_rad / kPathStepRad));
  const Eigen::Vector2d goal =
      *now.goal_distance_m *
      Eigen::Vector2d(std::sin(*now.goal_bearing_rad), std::cos(*now.goal_bearing_rad));
  // Where the agent is once its heading has turned by heading_rad.
  const auto on_arc = [&](double heading_rad) {
    return Eigen::Vector2d{side * radius_m * (1.0 - std::cos(heading_rad)),
                           radius_m * std::sin(heading_rad)};
  };
  const Eigen::Vector2d turned_at = on_arc(turn_rad);
  const Eigen::Vector2d own{0.0, speed_mps};
  Outline outline;
  for (const ObjectFeatures& object : now.objects) {
    extended_outline_of(object, agent, depth, outline);
    if (distance_to_outline(outline) <= clearance_m ||
        distance_to_outline(outline, turned_at, goal) <= clearance_m) {
      return false;
    }
    const std::optional<Eigen::Vector2d> relative =
        relative_velocity(object, agent, depth, static_closing_ratio);
    const Eigen::Vector2d ground =
        relative ? Eigen::Vector2d(*relative + own) : Eigen::Vector2d::Zero();
    for (int k = 1; k <= steps; ++k) {
      const double heading_rad = turn_rad * k / steps;
      // Where the agent is then, in a frame that moves with the object.
      if (distance_to_outline(outline, on_arc(heading_rad) - ground * (heading_rad / rate)) <=
          clearance_m) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace flowsteer::servo::detail
