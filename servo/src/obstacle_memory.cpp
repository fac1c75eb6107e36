#include "flowsteer/servo/obstacle_memory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "flat_ground_flow.hpp"

namespace flowsteer::servo {

namespace {

// sin(φ)/φ, exact to rounding at φ = 0.
double sinc(double phi) {
  return std::abs(phi) < 1e-4 ? 1.0 - phi * phi / 6.0 : std::sin(phi) / phi;
}

// The pixel column and row nearest the normalised point (x, y).
int column_of(const base::CameraIntrinsics& k, double x) {
  return static_cast<int>(std::lround(k.fx_px * x + k.cx_px));
}
int row_of(const base::CameraIntrinsics& k, double y) {
  return static_cast<int>(std::lround(k.fy_px * y + k.cy_px));
}

void require(bool ok, const std::string& what) {
  if (!ok) {
    throw std::invalid_argument("ObstacleMemoryOptions: " + what);
  }
}

}  // namespace

ObstacleMemory::ObstacleMemory(const base::CameraMount& mount, const ObstacleMemoryOptions& options)
    : options_(options),
      ground_(mount),
      static_foe_(mount.forward_foe()),
      cos_pitch_(std::cos(mount.pitch_rad)) {
  require(options.spacing_m > 0.0, "spacing_m must be positive");
  require(options.link_m >= 0.0, "link_m must not be negative");
  require(options.range_m > 0.0 && options.behind_m >= 0.0, "range_m and behind_m out of range");
  require(options.fade_s > 0.0 && options.confirm_s >= 0.0 && options.forget_s >= options.confirm_s,
          "fade_s, confirm_s or forget_s out of range");
  require(options.confirm_span_s >= 0.0 && options.confirm_span_s <= options.forget_s,
          "confirm_span_s out of range");
  require(options.ttc_tolerance >= 0.0, "ttc_tolerance must not be negative");
  require(options.evidence_height_m > 0.0, "evidence_height_m must be positive");
  require(options.column_height_m > 0.0, "column_height_m must be positive");
  require(options.column_flow_error_px >= 0.0, "column_flow_error_px must not be negative");
  require(options.min_forward_m > 0.0, "min_forward_m must be positive");
  require(options.capacity > 0, "capacity must be positive");
  const auto capacity = static_cast<std::size_t>(options.capacity);
  points_.reserve(capacity);
  recalled_.reserve(capacity);
  parent_.reserve(capacity);
  object_of_.reserve(capacity);
  objects_.reserve(capacity);
}

void ObstacleMemory::carry(double speed_mps, double turn_rate, double dt_s) {
  // The body turns by φ = ω_z dt (ω_z = −turn_rate, counter-clockwise) along an arc whose chord
  // is v dt (sinc φ, (1 − cos φ)/φ), and (1 − cos φ)/φ = sin(φ/2) sinc(φ/2). A static point p
  // is then R(−φ) (p − chord) in the new body frame.
  const double phi = -turn_rate * dt_s;
  const double travel_m = speed_mps * dt_s;
  const Eigen::Vector2d chord =
      travel_m * Eigen::Vector2d(sinc(phi), std::sin(0.5 * phi) * sinc(0.5 * phi));
  const double c = std::cos(phi);
  const double s = std::sin(phi);
  const auto carried = [&](const Eigen::Vector2d& position_m) -> Eigen::Vector2d {
    const Eigen::Vector2d d = position_m - chord;
    return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
  };
  for (Point& p : points_) {
    p.position_m = carried(p.position_m);
    p.first_seen_m = carried(p.first_seen_m);
  }
  std::erase_if(points_, [&](const Point& p) {
    return p.position_m.norm() > options_.range_m || p.position_m.x() < -options_.behind_m;
  });
}

bool ObstacleMemory::stands_still(const View& view, const GroundContact& contact,
                                  double speed_mps) const {
  // A contact below the image only bounds its foot's depth: no point is taken from it.
  if (!(speed_mps >= options_.min_speed_mps) || contact.below_image || contact.label < 0 ||
      static_cast<std::size_t>(contact.label) >= view.objects.size()) {
    return false;
  }
  const ObjectFeatures& o = view.objects[static_cast<std::size_t>(contact.label)];
  if (o.kind == RegionKind::visible && column_stands_upright(view, contact, speed_mps)) {
    return true;
  }
  // Ends with depths: the features found it rising above the horizon, standing on the ground
  // at both ends, which a patch of ground the ground test missed does not.
  if (o.kind != RegionKind::visible || o.status != MotionStatus::approaching || !o.fit.static_foe ||
      !o.min_x_depth_m || !o.max_x_depth_m) {
    return false;
  }
  // A static point at depth Z closes in at v cos θ along the optical axis: τ = Z / (v cos θ)
  // (CGF Eq. 5). A contact far from the depth the region's τ gives is not where it stands: floor
  // the segmentation joined to something further, or the feet of someone walking.
  const double static_depth_m = o.ttc_s * speed_mps * cos_pitch_;
  return std::abs(contact.depth_m - static_depth_m) <= options_.ttc_tolerance * static_depth_m;
}

bool ObstacleMemory::column_stands_upright(const View& view, const GroundContact& contact,
                                           double speed_mps) const {
  const FlowField& field = view.field;
  const base::CameraIntrinsics& k = field.intrinsics();
  const auto foot = ground_.point_at(contact.x, contact.ground_y);
  const auto top = foot ? ground_.image_of(*foot, options_.column_height_m) : std::nullopt;
  const int col = column_of(k, contact.x);
  const int foot_row = row_of(k, contact.y);
  if (!top || col < 0 || col >= field.width() || foot_row < 0 || foot_row >= field.height()) {
    return false;
  }
  const int first = std::clamp(row_of(k, top->y()), 0, foot_row);
  const double to_px = k.fx_px * field.interval_s();
  const double x = field.x(col);
  int in_region = 0;
  int telling = 0;  // rows where an upright surface and the floor move apart
  int upright = 0;  // of those, rows that move as the upright surface
  for (int row = first; row <= foot_row; ++row) {
    const Eigen::Vector2f& flow = field.at(col, row);
    if (view.segmentation.labels[field.index(col, row)] != contact.label || !flow.allFinite()) {
      continue;
    }
    ++in_region;
    const double y = field.y(row);
    const auto standing_flow =
        detail::upright_flow_at(ground_, x, y, foot->x(), speed_mps, field.interval_s());
    const auto floor_flow = detail::floor_flow_at(ground_, x, y, speed_mps, field.interval_s());
    if (!standing_flow || !floor_flow) {
      continue;
    }
    const Eigen::Vector2d& standing = *standing_flow;
    const Eigen::Vector2d& floor = *floor_flow;
    // The flow's error, and the fraction of the flow by which a static point's τ may be off.
    const double error_px =
        options_.column_flow_error_px + options_.ttc_tolerance * standing.norm() * to_px;
    if ((standing - floor).norm() * to_px <= error_px || standing.norm() * to_px <= error_px) {
      continue;
    }
    ++telling;
    const double off = (flow.cast<double>() - standing).norm();
    upright += off * to_px <= error_px && off < (flow.cast<double>() - floor).norm();
  }
  return telling >= 3 && 2 * upright > telling && 2 * in_region > foot_row - first;
}

void ObstacleMemory::remember(const Eigen::Vector2d& position_m) {
  Point* nearest = nullptr;
  double nearest2 = options_.spacing_m * options_.spacing_m;
  for (Point& p : points_) {
    if (const double d2 = (p.position_m - position_m).squaredNorm(); d2 < nearest2) {
      nearest2 = d2;
      nearest = &p;
    }
  }
  if (nearest != nullptr) {
    Point& p = *nearest;
    if (p.sight != Point::Sight::observed) {
      // A running mean over the last few sightings: odometry drifts, and a new sighting is
      // measured where the point is now.
      ++p.sightings;
      p.position_m += (position_m - p.position_m) / std::min(p.sightings, 4);
      p.unseen_s = 0.0;
      p.contradicted_s = 0.0;
      p.sight = Point::Sight::observed;
      // A sighting further than spacing_m from the first, before the point is confirmed, follows
      // something that moves (faster than spacing_m over confirm_span_s): it starts again here.
      if (!confirmed(p) &&
          (position_m - p.first_seen_m).squaredNorm() > options_.spacing_m * options_.spacing_m) {
        p.first_seen_m = p.position_m;
        p.sightings = 1;
        p.age_s = 0.0;
      }
    }
    return;
  }
  if (points_.size() == points_.capacity()) {
    return;
  }
  points_.push_back({position_m, position_m, next_id_, 1, 0.0, 0.0, 0.0, Point::Sight::observed});
  next_id_ = next_id_ == std::numeric_limits<std::int32_t>::max() ? kFirstId : next_id_ + 1;
}

ObstacleMemory::Point::Sight ObstacleMemory::sight_of(const View& view, const Point& point) const {
  const auto foot = ground_.image_of(point.position_m);
  const auto top = ground_.image_of(point.position_m, options_.evidence_height_m);
  if (!foot || !top) {
    return Point::Sight::out_of_view;
  }
  const FlowField& field = view.field;
  const base::CameraIntrinsics& k = field.intrinsics();
  const int col = column_of(k, foot->x());
  const int foot_row = row_of(k, foot->y());
  if (col < 0 || col >= field.width() || foot_row < 1 || foot_row >= field.height()) {
    return Point::Sight::out_of_view;
  }
  // The obstacle would stand in the rows above its foot, up to evidence_height_m.
  const int last = foot_row - 1;
  const int first = std::clamp(row_of(k, top->y()), 0, last);
  int floor_rows = 0;
  for (int row = first; row <= last; ++row) {
    const std::size_t i = field.index(col, row);
    const std::int32_t label = view.segmentation.labels[i];
    if (label < 0) {
      floor_rows += !view.ground_mask.empty() && view.ground_mask[i] != 0;
      continue;
    }
    const RegionKind kind = view.segmentation.kinds[static_cast<std::size_t>(label)];
    if (kind == RegionKind::visible) {
      return Point::Sight::covered;
    }
    floor_rows += kind == RegionKind::ground;
  }
  return floor_rows == last - first + 1 ? Point::Sight::contradicted : Point::Sight::unknown;
}

void ObstacleMemory::observe(const View& view, double speed_mps, double dt_s) {
  for (Point& p : points_) {
    p.age_s += dt_s;
    p.unseen_s += dt_s;
    p.sight = Point::Sight::unknown;
  }
  const double row = 1.0 / view.field.intrinsics().fy_px;
  for (const GroundContact& c : view.contacts) {
    if (!stands_still(view, c, speed_mps)) {
      continue;
    }
    // Where one row of the image spans more floor than spacing_m, a foot found a few rows off (as
    // a region's lower edge is) misplaces the point by several spacings: it is taken nearer.
    const auto p = ground_.point_at(c.x, c.ground_y);
    const auto row_further = ground_.point_at(c.x, c.ground_y - row);
    if (p && row_further && (*row_further - *p).norm() <= options_.spacing_m &&
        p->norm() <= options_.range_m) {
      remember(*p);
    }
  }
  for (Point& p : points_) {
    if (p.sight != Point::Sight::observed) {
      p.sight = sight_of(view, p);
      if (p.sight == Point::Sight::contradicted) {
        p.contradicted_s += dt_s;
      }
    }
  }
  std::erase_if(points_, [&](const Point& p) {
    return p.contradicted_s >= options_.fade_s || p.unseen_s > options_.forget_s ||
           (!confirmed(p) && p.unseen_s > options_.confirm_s);
  });
}

std::size_t ObstacleMemory::find(std::size_t i) {
  while (parent_[i] != i) {
    parent_[i] = parent_[parent_[i]];  // path halving
    i = parent_[i];
  }
  return i;
}

std::span<const ObjectFeatures> ObstacleMemory::recall(double speed_mps) {
  recalled_.clear();
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Point& p = points_[i];
    if (confirmed(p) && p.sight == Point::Sight::out_of_view &&
        p.position_m.x() >= options_.min_forward_m) {
      recalled_.push_back(i);
    }
  }
  const std::size_t n = recalled_.size();
  parent_.resize(n);
  std::iota(parent_.begin(), parent_.end(), std::size_t{0});
  const double link2 = options_.link_m * options_.link_m;
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      if ((points_[recalled_[a]].position_m - points_[recalled_[b]].position_m).squaredNorm() <=
          link2) {
        parent_[find(a)] = find(b);
      }
    }
  }
  // Each object in the image's terms at depths along the course: a point (forward, left) is at
  // Z = forward and image x = −left / forward, as the law places (x Z, Z) on the ground.
  object_of_.assign(n, -1);
  objects_.clear();
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    int& object = object_of_[find(k)];
    if (object < 0) {
      object = static_cast<int>(objects_.size());
      ObjectFeatures& f = objects_.emplace_back();
      f.source_id = std::numeric_limits<std::int32_t>::max();
      f.min_x = inf;
      f.max_x = -inf;
      f.ttc_s = inf;  // the nearest depth along the course, until the end
    }
    ObjectFeatures& f = objects_[static_cast<std::size_t>(object)];
    const Point& p = points_[recalled_[k]];
    const double z = p.position_m.x();
    const double x = -p.position_m.y() / z;
    f.source_id = std::min(f.source_id, p.id);  // the oldest point's: stable
    ++f.pixel_count;
    f.centre.x() += x;
    f.ttc_s = std::min(f.ttc_s, z);
    if (x < f.min_x) {
      f.min_x = x;
      f.min_x_depth_m = z;
    }
    if (x > f.max_x) {
      f.max_x = x;
      f.max_x_depth_m = z;
    }
    // The nearest point is at Z √(1 + x²).
    if (!f.nearest_depth_m ||
        p.position_m.norm() < *f.nearest_depth_m * std::sqrt(1.0 + f.nearest_x * f.nearest_x)) {
      f.nearest_x = x;
      f.nearest_depth_m = z;
    }
  }
  for (ObjectFeatures& f : objects_) {
    f.centre = {f.centre.x() / f.pixel_count, static_foe_.y()};
    f.width = f.max_x - f.min_x;
    f.fit.static_foe = true;
    // A static point closes in at the agent's speed: τ = Z / v, its FOE the static one.
    if (speed_mps > 0.0) {
      f.status = MotionStatus::approaching;
      f.ttc_s /= speed_mps;
      f.foe = static_foe_;
    } else {
      f.status = MotionStatus::lateral;
      f.ttc_s = inf;
    }
  }
  return objects_;
}

}  // namespace flowsteer::servo
