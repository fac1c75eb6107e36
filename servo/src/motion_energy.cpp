#include "flowsteer/servo/motion_energy.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

namespace {

// Below this |bearing| the goal is straight ahead and gives no side to pick.
constexpr double kGoalSideBearingRad = 0.05;
// Floor samples along the free path, metres apart.
constexpr double kPathSampleStepM = 0.25;
// Free space: every column's floor reaches this share of the rows up to the horizon.
constexpr double kFreeSpaceShare = 0.9;

void check_size(std::size_t actual, std::size_t expected, const char* what) {
  if (actual != expected) {
    throw std::invalid_argument(std::string("motion energy: ") + what + " has " +
                                std::to_string(actual) + " entries for " +
                                std::to_string(expected) + " pixels");
  }
}

double sign_of(double value) {
  return value >= 0.0 ? 1.0 : -1.0;
}

}  // namespace

const char* to_string(MotionEnergyMode mode) {
  switch (mode) {
    case MotionEnergyMode::goal:
      return "goal";
    case MotionEnergyMode::opening:
      return "opening";
    case MotionEnergyMode::energy:
      return "energy";
    case MotionEnergyMode::head_on:
      return "head_on";
    case MotionEnergyMode::danger:
      return "danger";
  }
  return "?";
}

void classify_by_ids(std::span<const std::int32_t> ids, std::span<PixelClass> out) {
  check_size(out.size(), ids.size(), "the class image");
  for (std::size_t i = 0; i < ids.size(); ++i) {
    out[i] = ids[i] >= 0           ? PixelClass::mass
             : ids[i] == kGroundId ? PixelClass::floor
                                   : PixelClass::empty;
  }
}

void classify_by_ground(const FlowField& derotated, const base::CameraMount& mount,
                        double speed_mps, const GroundRemovalOptions& ground, double still_flow,
                        std::span<std::uint8_t> ground_mask, std::span<PixelClass> out) {
  check_size(out.size(), derotated.size(), "the class image");
  check_size(ground_mask.size(), derotated.size(), "the ground mask");
  std::fill(ground_mask.begin(), ground_mask.end(), std::uint8_t{0});
  mark_ground(derotated, mount, speed_mps, ground, ground_mask);
  const FlatGround plane(mount);
  const auto flow = derotated.flow();
  for (int row = 0; row < derotated.height(); ++row) {
    for (int col = 0; col < derotated.width(); ++col) {
      const std::size_t i = derotated.index(col, row);
      if (ground_mask[i] != 0) {
        out[i] = PixelClass::floor;
      } else if (!plane.depth_at(derotated.x(col), derotated.y(row)) &&
                 !(flow[i].norm() >= still_flow)) {
        out[i] = PixelClass::empty;
      } else {
        out[i] = PixelClass::mass;
      }
    }
  }
}

MotionEnergyController::MotionEnergyController(const base::CameraIntrinsics& intrinsics,
                                               const base::CameraMount& mount,
                                               const MotionEnergyOptions& options,
                                               const MotionEnergyLimits& limits)
    : intrinsics_(intrinsics), mount_(mount), options_(options), limits_(limits) {
  intrinsics_.validate();
  mount_.validate();
  if (!(options.flow_weight >= 0.0 && options.flow_weight <= 1.0)) {
    throw std::invalid_argument("motion energy: flow_weight must be in [0, 1]");
  }
  const int width = intrinsics.width_px;
  const int height = intrinsics.height_px;
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  previous_.assign(pixels, 0.0F);
  ridge_.assign(static_cast<std::size_t>(width), -1);
  openings_.reserve(static_cast<std::size_t>(width));
  horizon_row_ = intrinsics.cy_px - intrinsics.fy_px * std::tan(mount.pitch_rad);
  corner_rise_rows_ = options.corner_rise * std::max(1.0, height - 1 - horizon_row_);

  // The danger zone is fixed in the image: the pixels that see the floor within
  // danger_distance_m ahead and half_width_m to either side, at the bottom centre.
  danger_zone_.assign(pixels, 0);
  const FlatGround plane(mount);
  const Eigen::Matrix3d camera_to_body = mount.camera_to_body();
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const Eigen::Vector2d p = intrinsics.normalise(col, row);
      const auto depth = plane.depth_at(p.x(), p.y());
      if (!depth) {
        continue;
      }
      const Eigen::Vector3d body = camera_to_body * (*depth * Eigen::Vector3d(p.x(), p.y(), 1.0));
      const double forward_m = body.x();
      const double lateral_m = body.y();
      if (forward_m <= options.danger_distance_m && std::abs(lateral_m) <= limits.half_width_m) {
        danger_zone_[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                     static_cast<std::size_t>(col)] = 1;
        ++danger_zone_pixels_;
      }
    }
  }
}

bool MotionEnergyController::free_path_to(double bearing_rad, double distance_m) const {
  // Blumberg's test is a straight line from the bottom centre of the image to the point of
  // interest that must cross no non-floor pixel. The agent is not a point: the floor is
  // checked along three such lines, the path's centre and its two edges half_width_m aside.
  const Eigen::Matrix3d body_to_camera = mount_.camera_to_body().transpose();
  const double h = mount_.height_m;
  const double c = std::cos(bearing_rad);
  const double s = std::sin(bearing_rad);
  const double range = std::min(distance_m, options_.free_path_range_m);
  const int width = intrinsics_.width_px;
  const int height = intrinsics_.height_px;
  // The ground point `along` the path and `aside` of it, in pixels; empty out of the view.
  auto pixel = [&](double along, double aside) -> std::optional<std::pair<int, int>> {
    // Body frame, y to the left; a positive bearing is to the right.
    const double forward = along * c - aside * s;
    const double left = -along * s - aside * c;
    // The ground point in the camera frame (as FlatGround: z_up = −h).
    const Eigen::Vector3d camera = body_to_camera * Eigen::Vector3d(forward, left, -h);
    if (camera.z() <= 0.0) {
      return std::nullopt;
    }
    const double col = intrinsics_.cx_px + intrinsics_.fx_px * camera.x() / camera.z();
    const double row = intrinsics_.cy_px + intrinsics_.fy_px * camera.y() / camera.z();
    if (row > height - 0.5 || col < -0.5 || col > width - 0.5) {
      return std::nullopt;
    }
    return std::pair{std::clamp(static_cast<int>(std::lround(col)), 0, width - 1),
                     static_cast<int>(std::lround(row))};
  };
  if (!pixel(range, 0.0)) {
    return false;  // the end of the path is out of the view
  }
  for (double along = kPathSampleStepM; along <= range + 1e-9; along += kPathSampleStepM) {
    for (const double aside : {-limits_.half_width_m, 0.0, limits_.half_width_m}) {
      // What the camera does not see (beside or under it, close by) is the danger zone's.
      const auto p = pixel(along, aside);
      if (p && p->second <= ridge_[static_cast<std::size_t>(p->first)]) {
        return false;
      }
    }
  }
  return true;
}

void MotionEnergyController::find_openings() {
  // Blumberg after Horswill: corners where the ridge height changes steeply between column i
  // and column i + d, an opening from a left corner (the ridge rises: the floor goes further)
  // to the next right corner (it falls). The image's edges count as corners.
  openings_.clear();
  const int width = intrinsics_.width_px;
  const int height = intrinsics_.height_px;
  const int step = std::max(1, static_cast<int>(std::lround(options_.corner_step * width)));
  auto floor_rows = [&](int col) { return height - 1 - ridge_[static_cast<std::size_t>(col)]; };
  auto push = [&](int first, int last) {
    if (last >= first) {
      const double x = (0.5 * (first + last) - intrinsics_.cx_px) / intrinsics_.fx_px;
      openings_.push_back({first, last, std::atan(x)});
    }
  };
  int start = 0;
  for (int col = 0; col + step < width; ++col) {
    const int change = floor_rows(col + step) - floor_rows(col);
    if (change < -corner_rise_rows_ && start >= 0) {
      push(start, col);
      start = -1;
    } else if (change > corner_rise_rows_ && start < 0) {
      start = col + step;
    }
  }
  if (start >= 0) {
    push(start, width - 1);
  }
}

base::Command MotionEnergyController::step(std::span<const float> intensity,
                                           std::span<const PixelClass> classes,
                                           const Percept& percept, const AgentState& agent) {
  check_size(intensity.size(), previous_.size(), "the image");
  check_size(classes.size(), previous_.size(), "the class image");
  const int width = intrinsics_.width_px;
  const int height = intrinsics_.height_px;
  const double fw = options_.flow_weight;

  // FM_ijt = |fw·(pixel_ijt − pixel_ij(t−1)) + (1 − fw)·po(i, j)| (Blumberg 1997). The paper's
  // floor is one flat colour and its background black: neither has a frame difference, so
  // only mass pixels carry one here, whatever texture the floor and sky are rendered with.
  double left = 0.0;
  double right = 0.0;
  int danger = 0;
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                            static_cast<std::size_t>(col);
      if (classes[i] != PixelClass::mass) {
        continue;
      }
      const double difference = has_previous_ ? intensity[i] - previous_[i] : 0.0;
      const double energy = std::abs(fw * difference + (1.0 - fw));
      if (2 * col + 1 < width) {
        left += energy;
      } else if (2 * col + 1 > width) {
        right += energy;
      }
      danger += danger_zone_[i];
    }
  }
  std::copy(intensity.begin(), intensity.end(), previous_.begin());
  has_previous_ = true;
  const double half_pixels = static_cast<double>(width / 2) * height;
  state_.energy_left = left / half_pixels;
  state_.energy_right = right / half_pixels;
  state_.danger_fraction =
      danger_zone_pixels_ > 0 ? static_cast<double>(danger) / danger_zone_pixels_ : 0.0;

  // The ridge: the first non-floor pixel of each column, from the bottom.
  double floor_left = 0.0;
  double floor_right = 0.0;
  int lowest_floor = height;
  for (int col = 0; col < width; ++col) {
    int row = height - 1;
    while (row >= 0 && classes[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                               static_cast<std::size_t>(col)] == PixelClass::floor) {
      --row;
    }
    ridge_[static_cast<std::size_t>(col)] = row;
    const int floor_rows = height - 1 - row;
    lowest_floor = std::min(lowest_floor, floor_rows);
    (2 * col + 1 < width ? floor_left : floor_right) += floor_rows;
  }
  state_.free_space = lowest_floor >= kFreeSpaceShare * (height - 1 - horizon_row_);
  find_openings();

  const std::optional<double>& goal = percept.goal_bearing_rad;
  state_.free_path =
      goal && std::isfinite(*goal) &&
      free_path_to(*goal, percept.goal_distance_m.value_or(options_.free_path_range_m));

  const double sum = state_.energy_left + state_.energy_right;
  const double difference = state_.energy_left - state_.energy_right;
  const bool head_on =
      0.5 * sum > options_.head_on_energy && std::abs(difference) < options_.head_on_balance * sum;
  const bool in_danger = state_.danger_fraction > options_.danger_fraction;
  if (!head_on && !in_danger) {
    state_.side = 0.0;
  } else if (state_.side == 0.0) {
    // Pick a side and keep it until the case is over: away from the half with more energy
    // when they differ, else toward the half with more floor, else toward the goal.
    if (std::abs(difference) >= options_.head_on_balance * sum && sum > 0.0) {
      state_.side = sign_of(difference);
    } else if (std::abs(floor_right - floor_left) / std::max(1, width / 2) > corner_rise_rows_) {
      state_.side = sign_of(floor_right - floor_left);
    } else if (goal && std::abs(*goal) > kGoalSideBearingRad) {
      state_.side = sign_of(*goal);
    } else {
      state_.side = 1.0;
    }
  }

  const double energy_turn = options_.steer_gain * difference;
  double turn = 0.0;
  double target_speed = limits_.preferred_speed_mps;
  if (in_danger) {
    state_.mode = MotionEnergyMode::danger;
    turn = state_.side * limits_.max_turn_rate;
    target_speed = 0.0;
  } else if (head_on) {
    state_.mode = MotionEnergyMode::head_on;
    turn = state_.side * limits_.max_turn_rate;
    target_speed = 0.5 * limits_.preferred_speed_mps;
  } else if (goal && (state_.free_path || state_.free_space)) {
    state_.mode = MotionEnergyMode::goal;
    turn = options_.goal_gain * *goal;
  } else if (goal && !openings_.empty()) {
    state_.mode = MotionEnergyMode::opening;
    const Opening* best = &openings_.front();
    for (const Opening& o : openings_) {
      if (std::abs(o.bearing_rad - *goal) < std::abs(best->bearing_rad - *goal)) {
        best = &o;
      }
    }
    turn = options_.goal_gain * best->bearing_rad + energy_turn;
  } else {
    state_.mode = MotionEnergyMode::energy;
    turn = energy_turn;
  }
  // Speed: a first-order approach to the target speed over one second.
  const double accel =
      std::clamp(target_speed - agent.speed_mps, -limits_.max_accel_mps2, limits_.max_accel_mps2);
  return {in_danger ? -limits_.max_accel_mps2 : accel,
          std::clamp(turn, -limits_.max_turn_rate, limits_.max_turn_rate)};
}

}  // namespace flowsteer::servo
