#pragma once

// Two ODrive axes as firmware 0.5.x presents them on a SocketCAN bus, for the VM tests
// (tests/vm): heartbeats every 20 ms, Set_Axis_Requested_State obeyed, Set_Input_Vel
// integrated into the position, encoder estimates on request. `fail_node` makes that axis
// report CONTROLLER_FAILED (0x200) and drop to idle; `silent_node` stops its heartbeat. A bus
// that goes down (ip link set ... down) does not end the simulation: it waits for the bus.

#include <linux/can.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <thread>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/drivers/odrive_can.hpp"

namespace flowsteer::vm_test {

class SimulatedAxes {
 public:
  SimulatedAxes(const std::string& interface, std::uint8_t left_node, std::uint8_t right_node)
      : socket_(interface), axes_{{left_node}, {right_node}}, thread_([this] { run(); }) {}
  ~SimulatedAxes() {
    stop_ = true;
    thread_.join();
  }
  SimulatedAxes(const SimulatedAxes&) = delete;
  SimulatedAxes& operator=(const SimulatedAxes&) = delete;

  std::atomic<int> fail_node{-1};
  std::atomic<int> silent_node{-1};  // sends no heartbeat (a cable pulled, a board reset)

 private:
  struct Axis {
    std::uint8_t node;
    std::uint8_t state = drivers::odrive::kAxisStateIdle;
    float vel_turns_per_s = 0.0f;
    float pos_turns = 0.0f;
  };

  void run() {
    while (!stop_) {
      try {
        serve();
      } catch (const std::exception&) {
        // The bus is down: try again once it may be back.
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
  }

  void serve() {
    namespace odrive = drivers::odrive;
    const double now_s = base::monotonic_now_s();
    for (Axis& axis : axes_) {
      axis.pos_turns += static_cast<float>(axis.vel_turns_per_s * (now_s - last_s_));
    }
    last_s_ = now_s;
    if (now_s - last_heartbeat_s_ >= 0.02) {
      last_heartbeat_s_ = now_s;
      for (Axis& axis : axes_) {
        odrive::Heartbeat hb;
        if (fail_node == axis.node) {
          hb.axis_error = 0x200;
          axis.state = odrive::kAxisStateIdle;
          axis.vel_turns_per_s = 0.0f;
        }
        hb.axis_state = axis.state;
        if (silent_node != axis.node) {
          socket_.send(odrive::heartbeat_frame(axis.node, hb), 0.1);
        }
      }
    }
    const auto received = socket_.receive(0.005);
    if (!received) {
      return;
    }
    for (Axis& axis : axes_) {
      if (odrive::node_of(received->frame.can_id) == axis.node) {
        obey(axis, received->frame);
      }
    }
  }

  void obey(Axis& axis, const can_frame& frame) {
    namespace odrive = drivers::odrive;
    const std::uint32_t cmd = odrive::cmd_of(frame.can_id);
    if (cmd == odrive::kSetAxisRequestedState && frame.can_dlc >= 4) {
      std::uint32_t requested = 0;
      std::memcpy(&requested, frame.data, 4);
      if (fail_node != axis.node) {
        axis.state = static_cast<std::uint8_t>(requested);
      }
    } else if (cmd == odrive::kSetInputVel && frame.can_dlc == 8) {
      std::memcpy(&axis.vel_turns_per_s, frame.data, 4);
    } else if (cmd == odrive::kGetEncoderEstimates && (frame.can_id & CAN_RTR_FLAG) != 0) {
      const float vel = axis.state == odrive::kAxisStateClosedLoop ? axis.vel_turns_per_s : 0;
      socket_.send(odrive::encoder_estimates_frame(axis.node, {axis.pos_turns, vel}), 0.1);
    }
  }

  drivers::CanSocket socket_;
  Axis axes_[2];
  double last_s_ = base::monotonic_now_s();
  double last_heartbeat_s_ = 0.0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace flowsteer::vm_test
