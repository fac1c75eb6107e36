#include "flowsteer/launch/steering_models.hpp"

#include <stdexcept>

namespace flowsteer::launch {

namespace {

// Derotated flow slower than this above the horizon is sky or far background for
// mass_from: ground: 0.01 normalised units per second is the flow of a point 100 m away
// passed at 1 m/s.
constexpr double kStillFlow = 0.01;

}  // namespace

GeometricPerception::GeometricPerception(const sim_camera::World& world, std::size_t agent,
                                         const base::CameraIntrinsics& intrinsics,
                                         const base::CameraMount& mount)
    : world_(world), agent_(agent), intrinsics_(intrinsics), mount_(mount) {}

std::span<const servo::ObjectFeatures> GeometricPerception::perceive() {
  return features_.compute(geometry_.bodies_seen_by(world_, agent_), intrinsics_, mount_,
                           world_.agents()[agent_].speed_mps);
}

MotionEnergySteering::MotionEnergySteering(const sim_camera::AgentSpec& agent,
                                           const base::CameraIntrinsics& intrinsics,
                                           const base::CameraMount& mount)
    : mass_from_ground_(agent.controller.mass_from == "ground"),
      mount_(mount),
      controller_(intrinsics, mount_, agent.controller.motion_energy,
                  {agent.preferred_speed_mps, agent.controller.max_accel_mps2,
                   agent.controller.max_turn_rate,
                   agent.radius_m + 0.5 * agent.controller.clearance_margin_m}),
      intensity_(static_cast<std::size_t>(intrinsics.width_px) *
                 static_cast<std::size_t>(intrinsics.height_px)),
      classes_(intensity_.size()),
      ground_mask_(mass_from_ground_ ? intensity_.size() : 0) {
  if (agent.leader) {
    throw std::invalid_argument("agent '" + agent.name +
                                "' follows a leader: a motion_energy controller steers to goals "
                                "only (use vision or geometric)");
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

}  // namespace flowsteer::launch
