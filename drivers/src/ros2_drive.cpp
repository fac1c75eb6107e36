#include "flowsteer/drivers/ros2_drive.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <numbers>
#include <stdexcept>

#include "flowsteer/base/bounds.hpp"
#include "flowsteer/base/clock.hpp"
#include "flowsteer/base/command.hpp"
#include "flowsteer/ros2_dds/participant.hpp"
#include "flowsteer/ros2_dds/topics.hpp"

namespace flowsteer::drivers {

namespace ros2 = recording::ros2;

namespace {

double wrapped(double angle_rad) {
  return std::remainder(angle_rad, 2.0 * std::numbers::pi);
}

ros2::Time realtime_now() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return {static_cast<std::int32_t>(now.tv_sec), static_cast<std::uint32_t>(now.tv_nsec)};
}

void require_topic(const std::string& topic, const char* field) {
  if (const auto problem = ros2_dds::topic_name_problem(topic)) {
    throw std::invalid_argument(std::string("ros2 drive: ") + field + " '" + topic +
                                "': " + *problem);
  }
}

}  // namespace

Ros2Drive::Ros2Drive(Ros2DriveConfig config)
    : config_(std::move(config)),
      name_("ros2 " + config_.cmd_vel_topic + " (domain " + std::to_string(config_.domain_id) +
            ")") {
  require_topic(config_.cmd_vel_topic, "cmd_vel topic");
  require_topic(config_.odom_topic, "odom topic");
  if (config_.domain_id < 0 || config_.domain_id > ros2_dds::kMaxDomainId) {
    throw std::invalid_argument("ros2 drive: domain id " + std::to_string(config_.domain_id) +
                                " not from 0 to " + std::to_string(ros2_dds::kMaxDomainId));
  }
  const std::pair<const char*, double> positive[] = {
      {"timeout_s", config_.timeout_s},
      {"connect_timeout_s", config_.connect_timeout_s},
      {"wheel_separation_m", config_.geometry.wheel_separation_m},
      {"wheel_radius_m", config_.geometry.wheel_radius_m}};
  for (const auto& [field, value] : positive) {
    if (!(value > 0.0)) {
      throw std::invalid_argument(std::string("ros2 drive: ") + field + " " +
                                  base::format_number(value) + " must be positive");
    }
  }
  stamped_command_ = std::make_unique<ros2_dds::TwistStamped>();
  stamped_command_->header.frame_id = config_.frame_id;
}

Ros2Drive::~Ros2Drive() = default;

void Ros2Drive::require_configured() const {
  if (!configured_) {
    throw DriveError("not configured");
  }
}

// From scratch each time (MobileBase configures again after a failure): no pose, odometry or
// endpoint of an earlier connection is kept.
void Ros2Drive::configure() {
  configured_ = false;
  active_ = false;
  last_odometry_s_.reset();
  last_pose_.reset();
  state_ = {};
  twist_.reset();
  twist_stamped_.reset();
  odometry_.reset();
  participant_.reset();
  const double deadline_s = base::monotonic_now_s() + config_.connect_timeout_s;
  const auto left_s = [&] { return std::max(0.0, deadline_s - base::monotonic_now_s()); };
  const std::string wait = " within " + base::format_number(config_.connect_timeout_s) +
                           " s: is the robot's base controller running, on this domain?";
  try {
    participant_ = std::make_unique<ros2_dds::Participant>(config_.domain_id);
    const ros2_dds::Qos qos;  // ROS 2's default: reliable, volatile, keep last 10
    if (config_.stamped) {
      twist_stamped_ = std::make_unique<ros2_dds::Publisher<ros2_dds::TwistStamped>>(
          *participant_, config_.cmd_vel_topic, qos);
    } else {
      twist_ = std::make_unique<ros2_dds::Publisher<ros2::Twist>>(*participant_,
                                                                  config_.cmd_vel_topic, qos);
    }
    odometry_ = std::make_unique<ros2_dds::Subscription<ros2::Odometry>>(*participant_,
                                                                         config_.odom_topic, qos);
    const bool subscribed = config_.stamped ? twist_stamped_->wait_for_subscriber(left_s())
                                            : twist_->wait_for_subscriber(left_s());
    if (!subscribed) {
      throw DriveError("no subscriber on " + config_.cmd_vel_topic + wait);
    }
    while (!last_odometry_s_ && odometry_->wait(left_s())) {
      take_odometry();
    }
  } catch (const ros2_dds::DdsError& error) {
    throw DriveError(error.what());
  }
  if (!last_odometry_s_) {
    throw DriveError("no odometry on " + config_.odom_topic + wait);
  }
  configured_ = true;
  publish({});
}

void Ros2Drive::activate() {
  require_configured();
  publish({});
  active_ = true;
}

void Ros2Drive::deactivate() {
  require_configured();
  active_ = false;
  publish_stop_and_flush();
}

void Ros2Drive::publish_stop_and_flush() {
  publish({});
  const bool acknowledged = config_.stamped
                                ? twist_stamped_->wait_for_acknowledgements(config_.timeout_s)
                                : twist_->wait_for_acknowledgements(config_.timeout_s);
  if (!acknowledged) {
    throw DriveError("the stop was not acknowledged within " +
                     base::format_number(config_.timeout_s) + " s");
  }
}

void Ros2Drive::publish(const BodyVelocity& body) {
  ros2::Twist twist;
  twist.linear.x = body.speed_mps;
  twist.angular.z = base::yaw_rate_of(body.turn_rate);
  try {
    if (config_.stamped) {
      stamped_command_->header.stamp = realtime_now();
      stamped_command_->twist = twist;
      twist_stamped_->publish(*stamped_command_);
    } else {
      twist_->publish(twist);
    }
  } catch (const ros2_dds::DdsError& error) {
    throw DriveError(error.what());
  }
}

void Ros2Drive::write(const WheelSpeeds& wheels) {
  require_configured();
  const bool stop = wheels.left_radps == 0.0 && wheels.right_radps == 0.0;
  if (!active_ && !stop) {
    throw DriveError("write while not active");
  }
  if (!std::isfinite(wheels.left_radps) || !std::isfinite(wheels.right_radps)) {
    publish({});
    active_ = false;
    throw DriveError("wheel speeds not finite: left " + base::format_number(wheels.left_radps) +
                     ", right " + base::format_number(wheels.right_radps) + " rad/s");
  }
  publish(stop ? BodyVelocity{} : from_wheels(wheels, config_.geometry));
}

// Wheel angles from the pose: the arc between two poses (its length from the chord along the
// mean heading, exact for a constant turn rate between them) and the change of yaw, split over
// the wheels as a differential base rolls them.
void Ros2Drive::take_odometry() {
  while (odometry_->take(message_)) {
    last_odometry_s_ = base::monotonic_now_s();
    const ros2::Pose& pose = message_.pose;
    if (last_pose_) {
      const double heading = last_pose_->orientation.yaw_rad();
      const double turn = wrapped(pose.orientation.yaw_rad() - heading);
      const double mid = heading + 0.5 * turn;
      const double chord_m = (pose.position.x - last_pose_->position.x) * std::cos(mid) +
                             (pose.position.y - last_pose_->position.y) * std::sin(mid);
      // Between two poses the base rolled an arc; its length is the chord's, lengthened.
      const double half = 0.5 * turn;
      const double forward_m = std::abs(half) > 1e-9 ? chord_m * half / std::sin(half) : chord_m;
      const double half_track_m = 0.5 * config_.geometry.wheel_separation_m;
      state_.odometry.left_rad +=
          (forward_m - turn * half_track_m) / config_.geometry.wheel_radius_m;
      state_.odometry.right_rad +=
          (forward_m + turn * half_track_m) / config_.geometry.wheel_radius_m;
    }
    last_pose_ = pose;
    state_.measured = to_wheels(
        {message_.twist.linear.x, base::turn_rate_of(message_.twist.angular.z)}, config_.geometry);
  }
}

DriveState Ros2Drive::read() {
  require_configured();
  try {
    take_odometry();
  } catch (const ros2_dds::DdsError& error) {
    throw DriveError(error.what());
  }
  const double silent_s = base::monotonic_now_s() - *last_odometry_s_;
  if (silent_s > config_.timeout_s) {
    active_ = false;
    try {
      publish({});
    } catch (const DriveError&) {
      // Best effort: the caller reports the silence, which is the cause.
    }
    throw DriveError("no odometry on " + config_.odom_topic + " for " +
                     base::format_number(std::round(silent_s * 1e3) / 1e3) + " s (timeout_s " +
                     base::format_number(config_.timeout_s) + ")");
  }
  return state_;
}

}  // namespace flowsteer::drivers
