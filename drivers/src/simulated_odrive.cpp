#include "flowsteer/drivers/simulated_odrive.hpp"

#include <linux/can.h>

#include <chrono>
#include <cstring>
#include <exception>

#include "flowsteer/base/clock.hpp"

namespace flowsteer::drivers {

namespace {
constexpr double kHeartbeatPeriod_s = 0.02;
// ODrive's CONTROLLER_FAILED axis error.
constexpr std::uint32_t kControllerFailed = 0x200;
}  // namespace

SimulatedOdrive::SimulatedOdrive(const std::string& interface, std::uint8_t left_node,
                                 std::uint8_t right_node)
    : socket_(interface), last_s_(base::monotonic_now_s()) {
  axes_[0].axis.node = left_node;
  axes_[1].axis.node = right_node;
  thread_ = std::thread([this] { run(); });
}

SimulatedOdrive::~SimulatedOdrive() {
  stop_ = true;
  thread_.join();
}

std::array<SimulatedOdrive::Axis, 2> SimulatedOdrive::axes() const {
  const std::lock_guard lock(mutex_);
  return {axes_[0].axis, axes_[1].axis};
}

void SimulatedOdrive::fail_axis(std::optional<std::uint8_t> node) {
  const std::lock_guard lock(mutex_);
  failed_node_ = node;
}

void SimulatedOdrive::silence_axis(std::optional<std::uint8_t> node) {
  const std::lock_guard lock(mutex_);
  silent_node_ = node;
}

void SimulatedOdrive::run() {
  while (!stop_) {
    try {
      serve();
    } catch (const std::exception&) {
      // The bus is down: try again once it may be back.
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
}

void SimulatedOdrive::serve() {
  const double now_s = base::monotonic_now_s();
  {
    const std::lock_guard lock(mutex_);
    for (AxisModel& model : axes_) {
      model.axis.pos_turns += model.axis.vel_turns_per_s * (now_s - last_s_);
    }
    last_s_ = now_s;
    if (now_s - last_heartbeat_s_ >= kHeartbeatPeriod_s) {
      last_heartbeat_s_ = now_s;
      for (AxisModel& model : axes_) {
        odrive::Heartbeat heartbeat;
        if (failed_node_ == model.axis.node) {
          heartbeat.axis_error = kControllerFailed;
          model.axis.state = odrive::kAxisStateIdle;
          model.axis.vel_turns_per_s = 0.0;
        }
        heartbeat.axis_state = model.axis.state;
        if (silent_node_ != model.axis.node) {
          socket_.send(odrive::heartbeat_frame(model.axis.node, heartbeat), 0.1);
        }
      }
    }
  }
  const std::optional<ReceivedCanFrame> received = socket_.receive(0.005);
  if (!received) {
    return;
  }
  const std::lock_guard lock(mutex_);
  for (AxisModel& model : axes_) {
    if (odrive::node_of(received->frame.can_id) == model.axis.node) {
      obey(model, *received);
    }
  }
}

void SimulatedOdrive::obey(AxisModel& model, const ReceivedCanFrame& received) {
  const can_frame& frame = received.frame;
  Axis& axis = model.axis;
  const std::uint32_t cmd = odrive::cmd_of(frame.can_id);
  if (cmd == odrive::kSetAxisRequestedState && frame.can_dlc >= 4) {
    std::uint32_t requested = 0;
    std::memcpy(&requested, frame.data, 4);
    if (failed_node_ != axis.node) {
      axis.state = static_cast<std::uint8_t>(requested);
    }
  } else if (cmd == odrive::kSetInputVel && frame.can_dlc == 8) {
    float setpoint = 0.0f;
    std::memcpy(&setpoint, frame.data, 4);
    if (setpoint != model.setpoint_turns_per_s || !axis.setpoint_changed_s) {
      axis.setpoint_changed_s = received.received_s;
    }
    model.setpoint_turns_per_s = setpoint;
    axis.moving_setpoints += setpoint != 0.0f ? 1 : 0;
  } else if (cmd == odrive::kGetEncoderEstimates && (frame.can_id & CAN_RTR_FLAG) != 0) {
    socket_.send(
        odrive::encoder_estimates_frame(axis.node, {static_cast<float>(axis.pos_turns),
                                                    static_cast<float>(axis.vel_turns_per_s)}),
        0.1);
  }
  axis.vel_turns_per_s =
      axis.state == odrive::kAxisStateClosedLoop ? model.setpoint_turns_per_s : 0.0;
}

}  // namespace flowsteer::drivers
