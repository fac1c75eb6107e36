#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "flowsteer/drivers/odrive_can.hpp"

namespace flowsteer::drivers {

// Two ODrive axes as firmware 0.5.x presents them on a SocketCAN bus (CAN Simple): heartbeats
// every 20 ms, Set_Axis_Requested_State obeyed, Set_Input_Vel taken as the axis's velocity at
// once (an ODrive's velocity loop settles in milliseconds, well within a 50 Hz command stream),
// the position integrated from it, encoder estimates sent on request. The device side of
// `OdriveCanDrive`, for the simulator in the loop (`flowsteer sil`) and the VM tests. It serves
// the bus on a thread of its own; a bus that goes down (ip link set ... down) is waited for.
class SimulatedOdrive {
 public:
  // Throws DriveError naming the interface when it does not exist.
  SimulatedOdrive(const std::string& interface, std::uint8_t left_node, std::uint8_t right_node);
  ~SimulatedOdrive();
  SimulatedOdrive(const SimulatedOdrive&) = delete;
  SimulatedOdrive& operator=(const SimulatedOdrive&) = delete;

  struct Axis {
    std::uint8_t node = 0;
    std::uint8_t state = odrive::kAxisStateIdle;
    // The velocity the motor turns at: the last Set_Input_Vel in closed-loop control, else 0.
    double vel_turns_per_s = 0.0;
    // The position the velocity integrates to, as encoder estimates report it.
    double pos_turns = 0.0;
    // When the last Set_Input_Vel that changed the setpoint arrived (the kernel's receive time
    // on base::monotonic_now_s()'s clock); none before the first.
    std::optional<double> setpoint_changed_s;
    // Set_Input_Vel frames received with a non-zero velocity: how many updates drove the axis.
    std::uint64_t moving_setpoints = 0;
  };
  // Left, then right, as they are now.
  std::array<Axis, 2> axes() const;

  // The axis reports CONTROLLER_FAILED (0x200) in its heartbeats and drops to idle; nullopt:
  // none.
  void fail_axis(std::optional<std::uint8_t> node);
  // The axis sends no heartbeat (a cable pulled, a board reset); nullopt: every axis sends.
  void silence_axis(std::optional<std::uint8_t> node);

 private:
  struct AxisModel {
    Axis axis;
    double setpoint_turns_per_s = 0.0;
  };
  void run();
  void serve();
  void obey(AxisModel& model, const ReceivedCanFrame& received);

  CanSocket socket_;
  mutable std::mutex mutex_;  // guards axes_ and the fault selections
  std::array<AxisModel, 2> axes_;
  std::optional<std::uint8_t> failed_node_;
  std::optional<std::uint8_t> silent_node_;
  double last_s_;
  double last_heartbeat_s_ = 0.0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace flowsteer::drivers
