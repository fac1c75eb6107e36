#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace flowsteer::drivers {

// Thrown by every drive operation that fails: the message names the device and what was wrong
// (errno text for a failed system call). A drive that throws has already tried to stop its
// motors; `MobileBase` then deactivates it.
class DriveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Angular speeds of the two wheels of a differential base, positive rolling forward.
struct WheelSpeeds {
  double left_radps = 0.0;
  double right_radps = 0.0;
};

// Cumulative wheel angles since configure(), positive rolling forward.
struct WheelOdometry {
  double left_rad = 0.0;
  double right_rad = 0.0;
};

// What a drive measured in its last read().
struct DriveState {
  WheelSpeeds measured;
  WheelOdometry odometry;
  // Faults the hardware reports that do not stop it (an axis error stops it and throws).
  std::vector<std::string> faults;
};

// A differential base's motor controller, with the lifecycle of a ros2_control hardware
// interface: configure() opens the device and checks that the controller answers, activate()
// enables the motors with a zero command, write() sends wheel speeds, read() collects feedback,
// deactivate() commands zero and disables the motors. A write() of zero is a stop and is sent
// in any phase once configured, also after a drive has stopped itself on a fault, so a caller
// can always try to stop the wheels. Every call either succeeds or throws DriveError; none
// blocks longer than the drive's configured timeout.
//
// Drives see wheel speeds only. Limits, the watchdog and the conversion from the controller's
// turn rate live in `CommandStage`, in front of every drive (see base.hpp).
class Drive {
 public:
  virtual ~Drive() = default;

  // For error messages and logs: the kind of drive and its device, e.g. "odrive vcan0".
  virtual std::string_view name() const = 0;

  virtual void configure() = 0;
  virtual void activate() = 0;
  virtual void deactivate() = 0;
  virtual DriveState read() = 0;
  virtual void write(const WheelSpeeds& wheels) = 0;
};

}  // namespace flowsteer::drivers
