#include "contact_time.hpp"

#include <algorithm>
#include <cmath>

#include "cost_term_helpers.hpp"

namespace flowsteer::servo::detail {

namespace {

// A point p of the object: |p + V t| = R at the smaller root.
void point_contact(const Eigen::Vector2d& p, const Eigen::Vector2d& v, double radius,
                   Contact& first) {
  const double a = v.squaredNorm();
  const double b = p.dot(v);
  const double c = p.squaredNorm() - radius * radius;
  const double discriminant = b * b - a * c;
  if (b >= 0.0 || a <= 0.0 || discriminant < 0.0) {
    return;
  }
  const double t = std::max(0.0, c / (-b + std::sqrt(discriminant)));
  if (t < first.time_s) {
    first.time_s = t;
    first.normal = (p + v * t).normalized();
  }
}

}  // namespace

void segment_contact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& v,
                     double radius_m, Contact& first) {
  point_contact(a, v, radius_m, first);
  point_contact(b, v, radius_m, first);
  const double length = (b - a).norm();
  if (!(length > 0.0)) {
    return;
  }
  const Eigen::Vector2d along = (b - a) / length;
  Eigen::Vector2d m{-along.y(), along.x()};
  if (m.dot(a) < 0.0) {
    m = -m;
  }
  const double closing_mps = -m.dot(v);
  const double distance_m = m.dot(a);
  if (closing_mps <= 0.0 || distance_m < radius_m) {
    return;
  }
  const double t = (distance_m - radius_m) / closing_mps;
  const double foot = -along.dot(a + v * t);
  if (foot >= 0.0 && foot <= length && t < first.time_s) {
    first.time_s = t;
    first.normal = m;
  }
}

Eigen::Vector2d nearest_on_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp(-a.dot(ab) / length2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

double distance_to_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return nearest_on_segment(a, b).norm();
}

void outline_contact(const Outline& outline, const Eigen::Vector2d& v, double radius_m,
                     Contact& first) {
  for (int i = 0; i + 1 < outline.count; ++i) {
    segment_contact(outline.points[i], outline.points[i + 1], v, radius_m, first);
  }
}

double distance_to_outline(const Outline& outline) {
  return distance_to_outline(outline, Eigen::Vector2d::Zero());
}

double distance_to_outline(const Outline& outline, const Eigen::Vector2d& from) {
  double distance_m = std::numeric_limits<double>::infinity();
  for (int i = 0; i + 1 < outline.count; ++i) {
    distance_m = std::min(
        distance_m, distance_to_segment(outline.points[i] - from, outline.points[i + 1] - from));
  }
  return distance_m;
}

double contact_while_braking_s(const Outline& outline, const Eigen::Vector2d& ground_velocity,
                               double speed_mps, double decel_mps2, double radius_m, double step_s,
                               double until_s) {
  if (!(step_s > 0.0)) {
    return std::numeric_limits<double>::infinity();
  }
  const double stop_s = speed_mps / decel_mps2;
  Outline moved = outline;
  for (double t = step_s; t <= until_s; t += step_s) {
    const double braking_s = std::min(t, stop_s);
    const double walked_m = speed_mps * braking_s - 0.5 * decel_mps2 * braking_s * braking_s;
    const Eigen::Vector2d shift = ground_velocity * t - Eigen::Vector2d{0.0, walked_m};
    for (int i = 0; i < outline.count; ++i) {
      moved.points[i] = outline.points[i] + shift;
    }
    if (distance_to_outline(moved) < radius_m) {
      return t;
    }
  }
  return std::numeric_limits<double>::infinity();
}

double distance_to_path_m(const Outline& outline, const Eigen::Vector2d& v, double half_width_m) {
  if (v.x() == 0.0) {
    return std::numeric_limits<double>::infinity();
  }
  double distance_m = std::numeric_limits<double>::infinity();
  for (int i = 0; i < outline.count; ++i) {
    const Eigen::Vector2d& p = outline.points[i];
    distance_m = std::min(distance_m, p.y() - p.x() * v.y() / v.x());
  }
  return distance_m - half_width_m * v.norm() / std::abs(v.x());
}

std::optional<Eigen::Vector2d> relative_velocity(const ObjectFeatures& object,
                                                 const AgentState& agent, const DepthGuess& depth,
                                                 double static_closing_ratio) {
  // A static object moves relative to the agent by the agent's own speed. Z/τ from the region's
  // mean depth and its fitted τ is the speed of no one point of it: for a wall along the path,
  // whose fit leans on its near pixels, it was three times the agent's, and a wall's far end 9 m
  // ahead came within the horizon.
  if (stands_still(object, agent, depth, static_closing_ratio) && object.has_foe() &&
      std::isfinite(object.foe.x())) {
    const double vz = -agent.speed_mps;
    return Eigen::Vector2d{object.foe.x() * vz, vz};
  }
  if (object.has_foe() && std::isfinite(object.ttc_s) && std::isfinite(object.foe.x())) {
    const double vz = -depth_scale(object, agent, depth).depth_m / object.ttc_s;
    return Eigen::Vector2d{object.foe.x() * vz, vz};
  }
  if (object.status == MotionStatus::lateral && object.moments.mean_inv_depth &&
      *object.moments.mean_inv_depth > 0.0) {
    return Eigen::Vector2d{object.moments.mean_u / *object.moments.mean_inv_depth, 0.0};
  }
  return std::nullopt;
}

void outline_of(const ObjectFeatures& object, const AgentState& agent, const DepthGuess& depth,
                Outline& outline) {
  const double depth_m = depth_scale(object, agent, depth).depth_m;
  const bool depths = depth.use_depth && object.min_x_depth_m && object.max_x_depth_m;
  const double left_m = depths ? *object.min_x_depth_m : depth_m;
  const double right_m = depths ? *object.max_x_depth_m : depth_m;
  outline.count = 0;
  outline.points[outline.count++] = {object.min_x * left_m, left_m};
  if (depths && object.nearest_depth_m && object.nearest_x > object.min_x &&
      object.nearest_x < object.max_x) {
    outline.points[outline.count++] = {object.nearest_x * *object.nearest_depth_m,
                                       *object.nearest_depth_m};
  }
  outline.points[outline.count++] = {object.max_x * right_m, right_m};
}

std::optional<StraightOn> straight_on(const ObjectFeatures& object, const AgentState& agent,
                                      const DepthGuess& depth, double static_closing_ratio,
                                      double radius_m) {
  if (object.kind != RegionKind::visible || !object.centre.allFinite()) {
    return std::nullopt;
  }
  const std::optional<Eigen::Vector2d> velocity =
      relative_velocity(object, agent, depth, static_closing_ratio);
  if (!velocity) {
    return std::nullopt;
  }
  StraightOn s;
  outline_of(object, agent, depth, s.outline);
  s.velocity = *velocity;
  s.radius_m = std::min(radius_m, 0.99 * distance_to_outline(s.outline));
  outline_contact(s.outline, s.velocity, s.radius_m, s.contact);
  return s;
}

void extended_outline_of(const ObjectFeatures& object, const AgentState& agent,
                         const DepthGuess& depth, Outline& outline) {
  // Further than the agent stops from at any speed it walks at.
  constexpr double kHiddenLength_m = 10.0;
  outline_of(object, agent, depth, outline);
  const auto extend = [&](bool cut, int end, int inner) {
    const Eigen::Vector2d out = outline.points[end] - outline.points[inner];
    if (cut && out.norm() > 1e-6) {
      outline.points[end] += kHiddenLength_m * out.normalized();
    }
  };
  extend(object.cut_left, 0, 1);
  extend(object.cut_right, outline.count - 1, outline.count - 2);
}

namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Whether the segments [a, b] and [c, d] cross or touch.
bool segments_cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                    const Eigen::Vector2d& d) {
  const double ab_c = cross(b - a, c - a);
  const double ab_d = cross(b - a, d - a);
  const double cd_a = cross(d - c, a - c);
  const double cd_b = cross(d - c, b - c);
  return ab_c * ab_d <= 0.0 && cd_a * cd_b <= 0.0;
}

}  // namespace

double distance_to_outline(const Outline& outline, const Eigen::Vector2d& from,
                           const Eigen::Vector2d& to) {
  double distance_m = std::numeric_limits<double>::infinity();
  for (int i = 0; i + 1 < outline.count; ++i) {
    const Eigen::Vector2d& a = outline.points[i];
    const Eigen::Vector2d& b = outline.points[i + 1];
    if (segments_cross(a, b, from, to)) {
      return 0.0;
    }
    distance_m = std::min(
        {distance_m, distance_to_segment(a - from, b - from), distance_to_segment(a - to, b - to),
         distance_to_segment(from - a, to - a), distance_to_segment(from - b, to - b)});
  }
  return distance_m;
}

double course_room_m(const ObjectFeatures& object, const AgentState& agent, const DepthGuess& depth,
                     double radius_m) {
  Outline outline;
  extended_outline_of(object, agent, depth, outline);
  const double now_m = distance_to_outline(outline);
  Contact contact;
  // Walking at 1 m/s towards a standing object: the contact's time is its distance.
  outline_contact(outline, {0.0, -1.0}, std::min(radius_m, 0.99 * now_m), contact);
  return contact.time_s;
}

}  // namespace flowsteer::servo::detail
