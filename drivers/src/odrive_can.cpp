#include "flowsteer/drivers/odrive_can.hpp"

#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "flowsteer/base/clock.hpp"

namespace flowsteer::drivers {

namespace {

static_assert(std::endian::native == std::endian::little,
              "CAN Simple payloads are little-endian; this code copies them as they are");

can_frame make_frame(std::uint8_t node_id, std::uint32_t cmd_id, std::uint8_t len) {
  can_frame frame{};
  frame.can_id = odrive::frame_id(node_id, cmd_id);
  frame.can_dlc = len;
  return frame;
}

template <typename T>
void put(can_frame& frame, std::size_t offset, T value) {
  std::memcpy(frame.data + offset, &value, sizeof value);
}

template <typename T>
T get(const can_frame& frame, std::size_t offset) {
  T value;
  std::memcpy(&value, frame.data + offset, sizeof value);
  return value;
}

// Waits for `events` until the deadline; false on timeout.
bool wait_fd(int fd, short events, double timeout_s, const std::string& what) {
  const double deadline_s = base::monotonic_now_s() + timeout_s;
  for (;;) {
    const double left_s = deadline_s - base::monotonic_now_s();
    pollfd pfd{fd, events, 0};
    const int ready = ::poll(&pfd, 1, left_s > 0.0 ? static_cast<int>(left_s * 1000.0) + 1 : 0);
    if (ready < 0) {
      if (errno == EINTR) {
        continue;
      }
      throw DriveError(what + ": poll: " + std::strerror(errno));
    }
    if (ready > 0 && (pfd.revents & (POLLERR | POLLNVAL)) != 0) {
      // SocketCAN reports a bus error this way; the pending socket error says which.
      int error = 0;
      socklen_t len = sizeof error;
      ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &len);
      throw DriveError(what + ": socket error: " + std::strerror(error != 0 ? error : EIO));
    }
    return ready > 0;
  }
}

// The kernel's receive stamp (SO_TIMESTAMPNS, CLOCK_REALTIME) moved onto the monotonic clock by
// its age; now when the stamp is missing or a clock step makes it look younger than nothing.
double receive_time_s(msghdr& message) {
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec stamp{};
      std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
      return base::monotonic_of_realtime_s(stamp.tv_sec, stamp.tv_nsec,
                                           std::numeric_limits<double>::infinity())
          .value_or(base::monotonic_now_s());
    }
  }
  return base::monotonic_now_s();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Codec

namespace odrive {

std::uint32_t frame_id(std::uint8_t node_id, std::uint32_t cmd_id) {
  return (static_cast<std::uint32_t>(node_id) << 5) | (cmd_id & 0x1f);
}
std::uint8_t node_of(canid_t id) {
  return static_cast<std::uint8_t>((id & CAN_SFF_MASK) >> 5);
}
std::uint32_t cmd_of(canid_t id) {
  return id & 0x1f;
}

can_frame set_axis_requested_state(std::uint8_t node_id, std::uint32_t state) {
  can_frame frame = make_frame(node_id, kSetAxisRequestedState, 4);
  put(frame, 0, state);
  return frame;
}

can_frame set_controller_modes(std::uint8_t node_id, std::int32_t control_mode,
                               std::int32_t input_mode) {
  can_frame frame = make_frame(node_id, kSetControllerModes, 8);
  put(frame, 0, control_mode);
  put(frame, 4, input_mode);
  return frame;
}

can_frame set_input_vel(std::uint8_t node_id, float vel_turns_per_s, float torque_ff_nm) {
  can_frame frame = make_frame(node_id, kSetInputVel, 8);
  put(frame, 0, vel_turns_per_s);
  put(frame, 4, torque_ff_nm);
  return frame;
}

can_frame get_encoder_estimates(std::uint8_t node_id) {
  // DLC 8 on the remote frame: some CAN controllers answer an RTR only when the lengths match.
  can_frame frame = make_frame(node_id, kGetEncoderEstimates, 8);
  frame.can_id |= CAN_RTR_FLAG;
  return frame;
}

can_frame heartbeat_frame(std::uint8_t node_id, const Heartbeat& heartbeat) {
  can_frame frame = make_frame(node_id, kHeartbeat, 8);
  put(frame, 0, heartbeat.axis_error);
  frame.data[4] = heartbeat.axis_state;
  frame.data[5] = heartbeat.motor_error ? 1 : 0;
  frame.data[6] = heartbeat.encoder_error ? 1 : 0;
  frame.data[7] = heartbeat.controller_error ? 1 : 0;
  return frame;
}

std::optional<Heartbeat> parse_heartbeat(const can_frame& frame) {
  if (frame.can_dlc < 5 || (frame.can_id & CAN_RTR_FLAG) != 0) {
    return std::nullopt;
  }
  Heartbeat heartbeat;
  heartbeat.axis_error = get<std::uint32_t>(frame, 0);
  heartbeat.axis_state = frame.data[4];
  // Firmware 0.5.x adds the motor, encoder and controller flags; older ones stop at byte 4.
  heartbeat.motor_error = frame.can_dlc > 5 && frame.data[5] != 0;
  heartbeat.encoder_error = frame.can_dlc > 6 && frame.data[6] != 0;
  // Bit 7 of byte 7 is "trajectory done", not an error.
  heartbeat.controller_error = frame.can_dlc > 7 && (frame.data[7] & 0x7f) != 0;
  return heartbeat;
}

can_frame encoder_estimates_frame(std::uint8_t node_id, const EncoderEstimates& estimates) {
  can_frame frame = make_frame(node_id, kGetEncoderEstimates, 8);
  put(frame, 0, estimates.pos_turns);
  put(frame, 4, estimates.vel_turns_per_s);
  return frame;
}

std::optional<EncoderEstimates> parse_encoder_estimates(const can_frame& frame) {
  if (frame.can_dlc < 8 || (frame.can_id & CAN_RTR_FLAG) != 0) {
    return std::nullopt;
  }
  return EncoderEstimates{get<float>(frame, 0), get<float>(frame, 4)};
}

std::string describe_axis_error(std::uint32_t axis_error) {
  static constexpr std::pair<std::uint32_t, const char*> kNames[] = {
      {0x00000001, "INVALID_STATE"},
      {0x00000040, "MOTOR_FAILED"},
      {0x00000080, "SENSORLESS_ESTIMATOR_FAILED"},
      {0x00000100, "ENCODER_FAILED"},
      {0x00000200, "CONTROLLER_FAILED"},
      {0x00000800, "WATCHDOG_TIMER_EXPIRED"},
      {0x00001000, "MIN_ENDSTOP_PRESSED"},
      {0x00002000, "MAX_ENDSTOP_PRESSED"},
      {0x00004000, "ESTOP_REQUESTED"},
      {0x00020000, "HOMING_WITHOUT_ENDSTOP"},
      {0x00040000, "OVER_TEMP"},
      {0x00080000, "UNKNOWN_POSITION"},
  };
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%08x", axis_error);
  std::string names;
  std::uint32_t rest = axis_error;
  for (const auto& [bit, name] : kNames) {
    if ((axis_error & bit) != 0) {
      names += (names.empty() ? "" : " | ") + std::string(name);
      rest &= ~bit;
    }
  }
  if (rest != 0) {
    char other[24];
    std::snprintf(other, sizeof other, "0x%x", rest);
    names += (names.empty() ? "" : " | ") + std::string(other);
  }
  return std::string(hex) + " (" + names + ")";
}

}  // namespace odrive

// ---------------------------------------------------------------------------------------------
// CanSocket

CanSocket::CanSocket(const std::string& interface) : interface_(interface) {
  const std::string where = "CAN interface " + interface_;
  if (interface_.empty() || interface_.size() >= IFNAMSIZ) {
    throw DriveError(where + ": not a valid interface name");
  }
  fd_.reset(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!fd_) {
    throw DriveError(where + ": socket(PF_CAN): " + std::strerror(errno) +
                     (errno == EAFNOSUPPORT ? " (is the can module loaded?)" : ""));
  }
  const unsigned index = ::if_nametoindex(interface_.c_str());
  if (index == 0) {
    throw DriveError(where + " not found: " + std::strerror(errno));
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    throw DriveError(where + ": bind: " + std::strerror(errno));
  }
  const int on = 1;
  if (::setsockopt(fd_.get(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) != 0) {
    throw DriveError(where + ": SO_TIMESTAMPNS: " + std::strerror(errno));
  }
}

void CanSocket::set_filters(const can_filter* filters, std::size_t count) {
  if (::setsockopt(fd_.get(), SOL_CAN_RAW, CAN_RAW_FILTER, filters,
                   static_cast<socklen_t>(count * sizeof(can_filter))) != 0) {
    throw DriveError("CAN interface " + interface_ + ": CAN_RAW_FILTER: " + std::strerror(errno));
  }
}

void CanSocket::send(const can_frame& frame, double timeout_s) {
  const double deadline_s = base::monotonic_now_s() + timeout_s;
  for (;;) {
    const ssize_t n = ::write(fd_.get(), &frame, sizeof frame);
    if (n == static_cast<ssize_t>(sizeof frame)) {
      return;
    }
    char id[16];
    std::snprintf(id, sizeof id, "0x%03x", frame.can_id & CAN_SFF_MASK);
    const std::string what = "CAN interface " + interface_ + ": send " + id;
    if (n >= 0) {
      throw DriveError(what + ": short write of " + std::to_string(n) + " bytes");
    }
    // ENOBUFS: the interface's queue is full (on a real bus: nobody acknowledges). Neither it
    // nor EAGAIN is fatal until the deadline.
    if (errno != EAGAIN && errno != ENOBUFS && errno != EINTR) {
      throw DriveError(
          what + ": " + std::strerror(errno) +
          (errno == ENETDOWN ? " (bring it up: ip link set " + interface_ + " up)" : ""));
    }
    const double left_s = deadline_s - base::monotonic_now_s();
    if (left_s <= 0.0) {
      throw DriveError(what + ": timed out after " + std::to_string(timeout_s) +
                       " s (bus off or nobody acknowledging?)");
    }
    // poll() does not report the end of ENOBUFS, so that case retries on a short sleep.
    if (errno == ENOBUFS) {
      ::usleep(1000);
    } else {
      wait_fd(fd_.get(), POLLOUT, left_s, what);
    }
  }
}

std::optional<ReceivedCanFrame> CanSocket::receive(double timeout_s) {
  for (;;) {
    ReceivedCanFrame received{};
    iovec payload{&received.frame, sizeof received.frame};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
    msghdr message{};
    message.msg_iov = &payload;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_.get(), &message, 0);
    if (n == static_cast<ssize_t>(sizeof received.frame)) {
      received.received_s = receive_time_s(message);
      return received;
    }
    if (n >= 0) {
      throw DriveError("CAN interface " + interface_ + ": short read of " + std::to_string(n) +
                       " bytes");
    }
    if (errno != EAGAIN && errno != EINTR) {
      throw DriveError("CAN interface " + interface_ + ": read: " + std::strerror(errno));
    }
    if (errno == EAGAIN && (timeout_s <= 0.0 || !wait_fd(fd_.get(), POLLIN, timeout_s,
                                                         "CAN interface " + interface_))) {
      return std::nullopt;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// OdriveCanDrive

OdriveCanDrive::OdriveCanDrive(OdriveCanConfig config)
    : config_(std::move(config)),
      name_("odrive " + config_.interface),
      axes_{Axis{config_.left, "left", {}, {}, {}, {}, 0.0},
            Axis{config_.right, "right", {}, {}, {}, {}, 0.0}} {
  for (const Axis& axis : axes_) {
    if (axis.config.node_id > odrive::kMaxNodeId) {
      throw std::invalid_argument("odrive: node id of the " + std::string(axis.side) +
                                  " axis must be 0..63");
    }
    if (axis.config.direction != 1.0 && axis.config.direction != -1.0) {
      throw std::invalid_argument("odrive: direction of the " + std::string(axis.side) +
                                  " axis must be 1 or -1");
    }
  }
  if (config_.left.node_id == config_.right.node_id) {
    throw std::invalid_argument("odrive: the two axes need different node ids");
  }
  if (!(config_.motor_turns_per_wheel_turn > 0.0) || !(config_.timeout_s > 0.0)) {
    throw std::invalid_argument("odrive: motor_turns_per_wheel_turn and timeout_s must be > 0");
  }
}

std::string OdriveCanDrive::axis_name(const Axis& axis) const {
  return "ODrive node " + std::to_string(axis.config.node_id) + " (" + axis.side + ") on " +
         config_.interface;
}

CanSocket& OdriveCanDrive::socket() {
  if (!socket_) {
    throw DriveError(name_ + ": not configured");
  }
  return *socket_;
}

void OdriveCanDrive::drain(double wait_s) {
  CanSocket& can = socket();
  double timeout_s = wait_s;
  while (const std::optional<ReceivedCanFrame> received = can.receive(timeout_s)) {
    timeout_s = 0.0;
    const can_frame* frame = &received->frame;
    if ((frame->can_id & (CAN_EFF_FLAG | CAN_ERR_FLAG)) != 0) {
      continue;
    }
    const std::uint8_t node = odrive::node_of(frame->can_id);
    const std::uint32_t cmd = odrive::cmd_of(frame->can_id);
    for (Axis& axis : axes_) {
      if (axis.config.node_id != node) {
        continue;
      }
      if (cmd == odrive::kHeartbeat) {
        if (const auto heartbeat = odrive::parse_heartbeat(*frame)) {
          axis.heartbeat = *heartbeat;
          axis.heartbeat_s = received->received_s;
        }
      } else if (cmd == odrive::kGetEncoderEstimates) {
        if (const auto estimates = odrive::parse_encoder_estimates(*frame)) {
          axis.estimates = *estimates;
          axis.estimates_s = received->received_s;
        }
      }
    }
  }
}

void OdriveCanDrive::stop_axes() noexcept {
  if (!socket_) {
    return;
  }
  for (const Axis& axis : axes_) {
    try {
      socket_->send(odrive::set_input_vel(axis.config.node_id, 0.0f, 0.0f), config_.timeout_s);
      socket_->send(odrive::set_axis_requested_state(axis.config.node_id, odrive::kAxisStateIdle),
                    config_.timeout_s);
    } catch (const DriveError&) {
      // Best effort: the other axis still gets its stop, and the caller reports the cause.
    }
  }
}

void OdriveCanDrive::fail(const std::string& message) {
  stop_axes();
  active_ = false;
  throw DriveError(message);
}

void OdriveCanDrive::check_axis_error(const Axis& axis) {
  const odrive::Heartbeat& hb = axis.heartbeat;
  if (hb.axis_error != 0 || hb.motor_error || hb.encoder_error || hb.controller_error) {
    std::string flags;
    flags += hb.motor_error ? ", motor error" : "";
    flags += hb.encoder_error ? ", encoder error" : "";
    flags += hb.controller_error ? ", controller error" : "";
    fail(axis_name(axis) + " reports axis error " + odrive::describe_axis_error(hb.axis_error) +
         flags);
  }
}

void OdriveCanDrive::check_errors(bool need_closed_loop) {
  const double now_s = base::monotonic_now_s();
  for (const Axis& axis : axes_) {
    if (!axis.heartbeat_s || now_s - *axis.heartbeat_s > config_.timeout_s) {
      fail("no heartbeat from " + axis_name(axis) + " for " + std::to_string(config_.timeout_s) +
           " s");
    }
    check_axis_error(axis);
    if (need_closed_loop && axis.heartbeat.axis_state != odrive::kAxisStateClosedLoop) {
      fail(axis_name(axis) + " left closed-loop control (axis state " +
           std::to_string(axis.heartbeat.axis_state) + ")");
    }
  }
}

template <typename Done>
void OdriveCanDrive::wait_for(Done done, const std::string& what, AxisErrors errors) {
  const double deadline_s = base::monotonic_now_s() + config_.timeout_s;
  for (;;) {
    bool all = true;
    for (const Axis& axis : axes_) {
      if (axis.heartbeat_s && errors == AxisErrors::fail) {
        check_axis_error(axis);
      }
      all = all && done(axis);
    }
    if (all) {
      return;
    }
    const double left_s = deadline_s - base::monotonic_now_s();
    if (left_s <= 0.0) {
      for (const Axis& axis : axes_) {
        if (!done(axis)) {
          fail(axis_name(axis) + ": " + what + " within " + std::to_string(config_.timeout_s) +
               " s");
        }
      }
    }
    drain(std::max(left_s, 0.0));
  }
}

void OdriveCanDrive::configure() {
  active_ = false;
  socket_.reset();
  socket_.emplace(config_.interface);
  // Only our two nodes' frames, so another device's traffic cannot fill the socket's queue.
  const can_filter filters[2] = {
      {odrive::frame_id(config_.left.node_id, 0), CAN_SFF_MASK & ~0x1fu},
      {odrive::frame_id(config_.right.node_id, 0), CAN_SFF_MASK & ~0x1fu}};
  socket_->set_filters(filters, 2);
  for (Axis& axis : axes_) {
    axis.heartbeat_s.reset();
    axis.estimates_s.reset();
  }
  wait_for([](const Axis& axis) { return axis.heartbeat_s.has_value(); },
           "no heartbeat (powered? node id and bitrate right?)");
  check_errors(false);
  for (const Axis& axis : axes_) {
    socket_->send(odrive::get_encoder_estimates(axis.config.node_id), config_.timeout_s);
  }
  wait_for([](const Axis& axis) { return axis.estimates_s.has_value(); },
           "no answer to Get_Encoder_Estimates");
  for (Axis& axis : axes_) {
    axis.start_pos_turns = axis.estimates.pos_turns;
  }
}

void OdriveCanDrive::activate() {
  CanSocket& can = socket();
  drain(0.0);
  check_errors(false);
  for (const Axis& axis : axes_) {
    const std::uint8_t node = axis.config.node_id;
    can.send(odrive::set_controller_modes(node, odrive::kControlModeVelocity,
                                          odrive::kInputModePassthrough),
             config_.timeout_s);
    can.send(odrive::set_input_vel(node, 0.0f, 0.0f), config_.timeout_s);
    can.send(odrive::set_axis_requested_state(node, odrive::kAxisStateClosedLoop),
             config_.timeout_s);
  }
  // The heartbeat that confirms the state change comes after the request; one sent before it
  // may still say idle.
  const double requested_s = base::monotonic_now_s();
  wait_for(
      [&](const Axis& axis) {
        return axis.heartbeat_s && *axis.heartbeat_s > requested_s &&
               axis.heartbeat.axis_state == odrive::kAxisStateClosedLoop;
      },
      "did not enter closed-loop control");
  active_ = true;
}

void OdriveCanDrive::deactivate() {
  CanSocket& can = socket();
  active_ = false;
  for (const Axis& axis : axes_) {
    can.send(odrive::set_input_vel(axis.config.node_id, 0.0f, 0.0f), config_.timeout_s);
    can.send(odrive::set_axis_requested_state(axis.config.node_id, odrive::kAxisStateIdle),
             config_.timeout_s);
  }
  // Only a heartbeat sent after the request confirms it. An axis error does not stop the wait:
  // the firmware drops an axis in error to idle, which is what is asked for here.
  const double requested_s = base::monotonic_now_s();
  wait_for(
      [&](const Axis& axis) {
        return axis.heartbeat_s && *axis.heartbeat_s > requested_s &&
               axis.heartbeat.axis_state == odrive::kAxisStateIdle;
      },
      "did not confirm idle", AxisErrors::ignore);
}

void OdriveCanDrive::write(const WheelSpeeds& wheels) {
  CanSocket& can = socket();
  if (!active_) {
    if (wheels.left_radps != 0.0 || wheels.right_radps != 0.0) {
      throw DriveError(name_ + ": write while not active");
    }
    for (const Axis& axis : axes_) {
      can.send(odrive::set_input_vel(axis.config.node_id, 0.0f, 0.0f), config_.timeout_s);
    }
    return;
  }
  const double turns_per_rad = config_.motor_turns_per_wheel_turn / (2.0 * std::numbers::pi);
  const double wheel_radps[2] = {wheels.left_radps, wheels.right_radps};
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    // Adding +0 turns a mirrored −0 into +0, so a stop reads as all-zero bytes on the bus.
    const float vel =
        static_cast<float>(wheel_radps[i] * turns_per_rad * axes_[i].config.direction) + 0.0f;
    if (!std::isfinite(vel)) {
      fail(name_ + ": wheel speed for the " + axes_[i].side + " axis not finite");
    }
    can.send(odrive::set_input_vel(axes_[i].config.node_id, vel, 0.0f), config_.timeout_s);
  }
  for (const Axis& axis : axes_) {
    can.send(odrive::get_encoder_estimates(axis.config.node_id), config_.timeout_s);
  }
}

DriveState OdriveCanDrive::read() {
  drain(0.0);
  check_errors(active_);
  DriveState state;
  const double now_s = base::monotonic_now_s();
  double* speeds[2] = {&state.measured.left_radps, &state.measured.right_radps};
  double* positions[2] = {&state.odometry.left_rad, &state.odometry.right_rad};
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    const Axis& axis = axes_[i];
    if (!axis.estimates_s || now_s - *axis.estimates_s > config_.timeout_s) {
      state.faults.push_back(axis_name(axis) + ": encoder estimates stale");
    }
    const double rad_per_turn = config_.wheel_rad_per_turn(axis.config);
    *speeds[i] = axis.estimates.vel_turns_per_s * rad_per_turn;
    *positions[i] = (axis.estimates.pos_turns - axis.start_pos_turns) * rad_per_turn;
  }
  return state;
}

}  // namespace flowsteer::drivers
