#include "motion_energy_steering.hpp"

#include <stdexcept>

namespace flowsteer::pipeline {

namespace {

// Derotated flow slower than this above the horizon is sky or far background for
// mass_from: ground: 0.01 normalised units per second is the flow of a point 100 m away
// passed at 1 m/s.
constexpr double kStillFlow = 0.01;

}  // namespace

MotionEnergySteering::MotionEnergySteering(const servo::ControllerConfig& config,
                                           const base::CameraIntrinsics& intrinsics,
                                           const base::CameraMount& mount,
                                           double preferred_speed_mps, double body_radius_m)
    : mass_from_ground_(config.mass_from == servo::MassSource::ground),
      mount_(mount),
      controller_(
          intrinsics, mount_, config.motion_energy,
          {preferred_speed_mps, config.max_accel_mps2, config.max_turn_rate, body_radius_m}),
      intensity_(static_cast<std::size_t>(intrinsics.width_px) *
                 static_cast<std::size_t>(intrinsics.height_px)),
      classes_(intensity_.size()),
      ground_mask_(mass_from_ground_ ? intensity_.size() : 0) {
  if (config.kind == servo::NavigationKind::following) {
    throw std::invalid_argument(
        "a motion_energy controller steers to goals only (use vision or geometric to follow a "
        "leader)");
  }
}

void MotionEnergySteering::step(const camera_io::Frame& frame, const servo::FlowField& derotated,
                                const servo::Percept& percept, const servo::AgentState& agent,
                                servo::ControlOutput& out) {
  const cv::Mat& image = frame.image;
  if (static_cast<std::size_t>(image.total()) != intensity_.size() || image.type() != CV_8UC3) {
    throw std::invalid_argument("motion energy: the frame is not the camera's 8-bit BGR size");
  }
  // Luma (ITU-R BT.601) in [0, 1]: the paper differences RGB values; one channel suffices.
  for (int row = 0; row < image.rows; ++row) {
    const auto* bgr = image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < image.cols; ++col) {
      intensity_[static_cast<std::size_t>(row * image.cols + col)] =
          (0.114F * bgr[col][0] + 0.587F * bgr[col][1] + 0.299F * bgr[col][2]) / 255.0F;
    }
  }
  if (mass_from_ground_) {
    servo::classify_by_ground(derotated, mount_, agent.speed_mps, {}, kStillFlow, ground_mask_,
                              classes_);
  } else {
    if (!frame.sim) {
      throw std::invalid_argument("motion energy: mass_from: ids needs the simulator's ids");
    }
    const cv::Mat& ids = frame.sim->object_ids;
    servo::classify_by_ids({ids.ptr<std::int32_t>(), ids.total()}, classes_);
  }
  out.command = controller_.step(intensity_, classes_, percept, agent);
  out.unclamped = out.command;
  out.cost = 0.0;
  out.terms.clear();
}

}  // namespace flowsteer::pipeline
