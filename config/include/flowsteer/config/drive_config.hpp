#pragma once

#include <memory>
#include <string>
#include <variant>

#include "flowsteer/drivers/command_stage.hpp"
#include "flowsteer/drivers/mobile_base.hpp"
#include "flowsteer/drivers/odrive_can.hpp"
#include "flowsteer/drivers/ros2_drive.hpp"
#include "flowsteer/drivers/serial_drives.hpp"
#include "flowsteer/drivers/sim_base.hpp"

namespace flowsteer::config {

// The `drive:` section of a launch file (fields in drivers/README.md): which drive, its
// settings, and the command stage in front of it.
struct DriveSection {
  std::variant<drivers::SimBaseConfig, drivers::OdriveCanConfig, drivers::ArduinoBridgeConfig,
               drivers::RoboClawConfig, drivers::Ros2DriveConfig>
      drive;
  drivers::CommandStageConfig stage;
  double loop_rate_hz = 50.0;
};

// Reads the `drive:` mapping of a launch file. Throws base::ConfigError naming the file, line,
// column and field of the first problem (an unknown type or key, a setting out of range, a
// loop period not well below the watchdog timeout).
DriveSection parse_drive_section(const std::string& yaml_text, const std::string& source_name);

// Builds the base the section describes; nothing is opened until MobileBase::configure().
std::unique_ptr<drivers::MobileBase> make_base(const DriveSection& section);

}  // namespace flowsteer::config
