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

// Beyond this bearing a column has no image coordinate worth keeping (tan grows without bound).
constexpr double kMaxBearingRad = 0.49 * std::numbers::pi;

// A direction at bearing β (x = sin β right, z = cos β forward) seen from a frame turned right
// by turn_rad: bearing β − turn_rad.
Eigen::Vector2d turned(const Eigen::Vector2d& v, double turn_rad) {
  const double c = std::cos(turn_rad);
  const double s = std::sin(turn_rad);
  return {v.x() * c - v.y() * s, v.y() * c + v.x() * s};
}

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
  const Eigen::Vector2d after = turned(*relative + own, turn_rad) - own;
  if (!(after.y() < 0.0)) {
    object.status = MotionStatus::receding;
    object.ttc_s = std::numeric_limits<double>::infinity();
    return;
  }
  object.foe.x() = after.x() / after.y();
  object.ttc_s = before.ttc_s * centre_depth_factor * relative->y() / after.y();
}

}  // namespace

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

}  // namespace flowsteer::servo::detail
