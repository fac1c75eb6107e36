#pragma once

#include <memory>
#include <optional>
#include <string>

#include "flowsteer/base/command.hpp"
#include "flowsteer/drivers/command_stage.hpp"
#include "flowsteer/drivers/drive.hpp"

namespace flowsteer::drivers {

enum class Lifecycle { unconfigured, inactive, active, failed };

// What the control loop learns from the base in one update().
struct BaseState {
  StageOutput sent;       // the command stage's decision, as written to the drive
  BodyVelocity measured;  // from the measured wheel speeds: feeds derotation and the controller
  DriveState drive;       // wheel speeds, odometry, non-fatal faults
};

// A command stage in front of a drive: the one thing the control loop talks to. Every failure
// of the drive leaves the base stopped (zero written, drive deactivated, both best effort) and
// the base in Lifecycle::failed before the DriveError reaches the caller.
class MobileBase {
 public:
  // Throws std::invalid_argument on a bad configuration or a null drive.
  MobileBase(std::unique_ptr<Drive> drive, const CommandStageConfig& config);
  // Deactivates an active drive; errors are swallowed since a destructor cannot report them.
  ~MobileBase();
  MobileBase(const MobileBase&) = delete;
  MobileBase& operator=(const MobileBase&) = delete;

  void configure();
  void activate(double now_s);
  void deactivate();

  // A fresh command from the controller; see CommandStage::command.
  std::optional<std::string> command(const base::Command& command, double now_s);
  // Runs the command stage, writes the wheel speeds and reads the drive's state. Call at the
  // loop rate: the drive needs a steady stream and the watchdog needs a clock.
  BaseState update(double now_s);

  // Latches the stop and writes zero to the drive at once, not at the next update().
  void emergency_stop();
  void clear_emergency_stop();

  Lifecycle lifecycle() const { return lifecycle_; }
  const Drive& drive() const { return *drive_; }
  const CommandStage& stage() const { return stage_; }

 private:
  // Stops and deactivates the drive after a failure, then rethrows it with the drive's name.
  [[noreturn]] void fail(const std::string& during, const std::exception& error);
  void require(Lifecycle expected, const char* operation) const;

  std::unique_ptr<Drive> drive_;
  CommandStage stage_;
  Lifecycle lifecycle_ = Lifecycle::unconfigured;
};

}  // namespace flowsteer::drivers
