#include "flowsteer/config/drive_config.hpp"

#include "drive_reader.hpp"
#include "flowsteer/config/field_bounds.hpp"
#include "flowsteer/ros2_dds/topics.hpp"
#include "ros2_reader.hpp"

namespace flowsteer::config {

namespace {

drivers::SerialConfig read_serial(const base::YamlReader& r, const YAML::Node& node,
                                  const std::string& field, int default_baud) {
  drivers::SerialConfig serial;
  if (!node["device"]) {
    r.fail(node, field + ".device", "missing: which serial device, e.g. /dev/ttyACM0?");
  }
  serial.device = r.text(node, field, "device", "", true);
  serial.baud = node["baud"] ? r.bounded_integer(node["baud"], field + ".baud") : default_baud;
  serial.timeout_s = r.bounded(node, field, "timeout_s", serial.timeout_s);
  return serial;
}

drivers::OdriveAxisConfig read_axis(const base::YamlReader& r, const YAML::Node& node,
                                    const std::string& field, drivers::OdriveAxisConfig axis) {
  if (!node) {
    return axis;
  }
  r.only_keys(node, field, {"node_id", "direction"});
  if (node["node_id"]) {
    axis.node_id =
        static_cast<std::uint8_t>(r.bounded_integer(node["node_id"], field + ".node_id"));
  }
  axis.direction = r.number(node, field, "direction", axis.direction);
  if (axis.direction != 1.0 && axis.direction != -1.0) {
    r.fail(node["direction"], field + ".direction", "must be 1 or -1");
  }
  return axis;
}

// The section with a drive type's own settings: `odrive` for odrive_can.
std::string own_section(const std::string& type) {
  return type == "odrive_can" ? "odrive" : type;
}

// The drive's type. Settings of another drive than the chosen one are a mistake, not something
// to ignore.
std::string read_type(const base::YamlReader& r, const YAML::Node& drive) {
  const std::string type = r.word(drive, "drive", "type",
                                  {"sim", "odrive_can", "arduino_bridge", "roboclaw", "ros2"}, "");
  if (type.empty()) {
    r.fail(drive, "drive.type", "missing: sim, odrive_can, arduino_bridge, roboclaw or ros2");
  }
  const std::string own = own_section(type);
  for (const char* other : {"sim", "odrive", "arduino_bridge", "roboclaw", "ros2"}) {
    if (drive[other] && own != other) {
      r.fail(drive[other], std::string("drive.") + other,
             "settings for another drive than type '" + type + "'");
    }
  }
  return type;
}

void read_geometry(const base::YamlReader& r, const YAML::Node& g,
                   drivers::WheelGeometry& geometry) {
  r.only_keys(g, "drive.geometry", {"wheel_separation_m", "wheel_radius_m"});
  geometry.wheel_separation_m =
      r.bounded(g, "drive.geometry", "wheel_separation_m", geometry.wheel_separation_m);
  geometry.wheel_radius_m =
      r.bounded(g, "drive.geometry", "wheel_radius_m", geometry.wheel_radius_m);
}

void read_limits(const base::YamlReader& r, const YAML::Node& l, drivers::CommandLimits& lim) {
  r.only_keys(l, "drive.limits",
              {"max_speed_mps", "max_reverse_speed_mps", "max_accel_mps2", "max_turn_rate",
               "max_wheel_speed_radps"});
  lim.max_speed_mps = r.bounded(l, "drive.limits", "max_speed_mps", lim.max_speed_mps);
  lim.max_reverse_speed_mps =
      r.bounded(l, "drive.limits", "max_reverse_speed_mps", lim.max_reverse_speed_mps);
  lim.max_accel_mps2 = r.bounded(l, "drive.limits", "max_accel_mps2", lim.max_accel_mps2);
  lim.max_turn_rate = r.bounded(l, "drive.limits", "max_turn_rate", lim.max_turn_rate);
  lim.max_wheel_speed_radps =
      r.bounded(l, "drive.limits", "max_wheel_speed_radps", lim.max_wheel_speed_radps);
}

void read_watchdog(const base::YamlReader& r, const YAML::Node& w,
                   drivers::WatchdogConfig& watchdog) {
  r.only_keys(w, "drive.watchdog", {"timeout_s", "ramp_s"});
  watchdog.timeout_s = r.bounded(w, "drive.watchdog", "timeout_s", watchdog.timeout_s);
  watchdog.ramp_s = r.bounded(w, "drive.watchdog", "ramp_s", watchdog.ramp_s);
  if (watchdog.ramp_s > watchdog.timeout_s) {
    r.fail(w["ramp_s"], "drive.watchdog.ramp_s", "must not exceed timeout_s");
  }
}

drivers::SimBaseConfig read_sim(const base::YamlReader& r, const YAML::Node& node,
                                const std::string& field, const drivers::WheelGeometry& geometry) {
  drivers::SimBaseConfig c;
  c.geometry = geometry;
  if (node) {
    r.only_keys(node, field, {"wheel_time_constant_s"});
    c.wheel_time_constant_s = r.bounded(node, field, "wheel_time_constant_s", 0.0);
  }
  return c;
}

drivers::OdriveCanConfig read_odrive_can(const base::YamlReader& r, const YAML::Node& node,
                                         const std::string& field) {
  drivers::OdriveCanConfig c;
  if (!node) {
    return c;
  }
  r.only_keys(node, field,
              {"can_interface", "left", "right", "motor_turns_per_wheel_turn", "timeout_s"});
  c.interface = r.text(node, field, "can_interface", c.interface, true);
  c.left = read_axis(r, node["left"], field + ".left", c.left);
  c.right = read_axis(r, node["right"], field + ".right", c.right);
  if (c.left.node_id == c.right.node_id) {
    r.fail(node, field, "left and right need different node ids");
  }
  c.motor_turns_per_wheel_turn =
      r.bounded(node, field, "motor_turns_per_wheel_turn", c.motor_turns_per_wheel_turn);
  c.timeout_s = r.bounded(node, field, "timeout_s", c.timeout_s);
  return c;
}

// A ROS 2 base controller: its topics default to diff_drive_controller's remapped names.
drivers::Ros2DriveConfig read_ros2(const base::YamlReader& r, const YAML::Node& node,
                                   const std::string& field,
                                   const drivers::WheelGeometry& geometry) {
  drivers::Ros2DriveConfig c;
  c.geometry = geometry;
  const YAML::Node settings = node ? node : YAML::Node(YAML::NodeType::Map);
  r.only_keys(settings, field, {"domain_id", "cmd_vel", "odom", "timeout_s", "connect_timeout_s"});
  c.domain_id = read_ros2_domain_id(r, settings, field);

  const std::string cmd_vel_field = field + ".cmd_vel";
  const YAML::Node cmd_vel = settings["cmd_vel"];
  if (cmd_vel) {
    r.only_keys(cmd_vel, cmd_vel_field, {"topic", "type", "frame_id"});
  }
  const std::string twist = ros2_dds::ros2_type_name<recording::ros2::Twist>();
  const std::string twist_stamped = ros2_dds::ros2_type_name<ros2_dds::TwistStamped>();
  const Ros2Topic command =
      read_ros2_topic(r, cmd_vel, cmd_vel_field, {c.cmd_vel_topic, twist}, {twist, twist_stamped});
  c.cmd_vel_topic = command.topic;
  c.stamped = command.type == twist_stamped;
  if (cmd_vel && cmd_vel["frame_id"]) {
    if (!c.stamped) {
      r.fail(cmd_vel["frame_id"], cmd_vel_field + ".frame_id",
             "only a " + twist_stamped + " has a frame_id");
    }
    c.frame_id = r.text(cmd_vel, cmd_vel_field, "frame_id", c.frame_id, true);
  }

  const std::string odom_field = field + ".odom";
  const YAML::Node odom = settings["odom"];
  if (odom) {
    r.only_keys(odom, odom_field, {"topic", "type"});
  }
  const std::string odometry = ros2_dds::ros2_type_name<recording::ros2::Odometry>();
  c.odom_topic = read_ros2_topic(r, odom, odom_field, {c.odom_topic, odometry}, {odometry}).topic;
  c.timeout_s = r.bounded(settings, field, "timeout_s", c.timeout_s);
  c.connect_timeout_s = r.bounded(settings, field, "connect_timeout_s", c.connect_timeout_s);
  return c;
}

// What every serial drive needs: its section, with the encoder's ticks.
void require_serial_settings(const base::YamlReader& r, const YAML::Node& drive,
                             const YAML::Node& node, const std::string& field) {
  if (!node) {
    r.fail(drive, field, "missing: the serial drive's settings (device, ticks_per_wheel_rev)");
  }
  if (!node.IsMap()) {
    r.fail(node, field, "expected a mapping (device, ticks_per_wheel_rev, ...)");
  }
  if (!node["ticks_per_wheel_rev"]) {
    r.fail(node, field + ".ticks_per_wheel_rev", "missing: encoder ticks per wheel turn");
  }
}

drivers::ArduinoBridgeConfig read_arduino_bridge(const base::YamlReader& r, const YAML::Node& node,
                                                 const std::string& field) {
  r.only_keys(node, field,
              {"device", "baud", "timeout_s", "ticks_per_wheel_rev", "pid_rate_hz", "boot_wait_s"});
  drivers::ArduinoBridgeConfig c;
  c.serial = read_serial(r, node, field, 57600);
  c.ticks_per_wheel_rev = r.bounded(node, field, "ticks_per_wheel_rev", 0.0);
  c.pid_rate_hz = r.bounded(node, field, "pid_rate_hz", c.pid_rate_hz);
  c.boot_wait_s = r.bounded(node, field, "boot_wait_s", c.boot_wait_s);
  return c;
}

drivers::RoboClawConfig read_roboclaw(const base::YamlReader& r, const YAML::Node& node,
                                      const std::string& field) {
  r.only_keys(node, field,
              {"device", "baud", "timeout_s", "address", "ticks_per_wheel_rev", "board_timeout_s",
               "left_is_m1"});
  drivers::RoboClawConfig c;
  c.serial = read_serial(r, node, field, 38400);
  if (node["address"]) {
    c.address = static_cast<std::uint8_t>(r.bounded_integer(node["address"], field + ".address"));
  }
  c.ticks_per_wheel_rev = r.bounded(node, field, "ticks_per_wheel_rev", 0.0);
  c.board_timeout_s = r.bounded(node, field, "board_timeout_s", c.board_timeout_s);
  c.left_is_m1 = r.boolean(node, field, "left_is_m1", c.left_is_m1);
  return c;
}

}  // namespace

DriveSection parse_drive_section(const std::string& yaml_text, const std::string& source_name) {
  const YAML::Node root = base::load_yaml(yaml_text, source_name);
  const YAML::Node drive = root.IsMap() ? root["drive"] : YAML::Node();
  if (!drive) {
    throw base::ConfigError(source_name, 1, 1, "drive",
                            "missing: the launch file has no drive section");
  }
  return read_drive(base::YamlReader(source_name, robot_launch_bounds()), drive);
}

DriveSection read_drive(const base::YamlReader& r, const YAML::Node& drive) {
  r.only_keys(drive, "drive",
              {"type", "loop_rate_hz", "geometry", "limits", "watchdog", "sim", "odrive",
               "arduino_bridge", "roboclaw", "ros2"});
  DriveSection s;
  const std::string type = read_type(r, drive);
  s.loop_rate_hz = r.bounded(drive, "drive", "loop_rate_hz", s.loop_rate_hz);
  if (const YAML::Node g = drive["geometry"]) {
    read_geometry(r, g, s.stage.geometry);
  }
  if (const YAML::Node l = drive["limits"]) {
    read_limits(r, l, s.stage.limits);
  }
  if (const YAML::Node w = drive["watchdog"]) {
    read_watchdog(r, w, s.stage.watchdog);
  }
  // The watchdog must see several loop periods before it trips.
  if (1.0 / s.loop_rate_hz > 0.5 * s.stage.watchdog.timeout_s) {
    r.fail(drive["loop_rate_hz"] ? drive["loop_rate_hz"] : drive, "drive.loop_rate_hz",
           "one loop period must be at most half of watchdog.timeout_s");
  }

  const std::string own = own_section(type);
  const YAML::Node own_node = drive[own];
  const std::string field = "drive." + own;
  if (type == "sim") {
    s.drive = read_sim(r, own_node, field, s.stage.geometry);
  } else if (type == "odrive_can") {
    s.drive = read_odrive_can(r, own_node, field);
  } else if (type == "ros2") {
    s.drive = read_ros2(r, own_node, field, s.stage.geometry);
  } else {
    require_serial_settings(r, drive, own_node, field);
    if (type == "arduino_bridge") {
      s.drive = read_arduino_bridge(r, own_node, field);
    } else {
      s.drive = read_roboclaw(r, own_node, field);
    }
  }
  return s;
}

std::unique_ptr<drivers::MobileBase> make_base(const DriveSection& section) {
  std::unique_ptr<drivers::Drive> drive = std::visit(
      [](const auto& config) -> std::unique_ptr<drivers::Drive> {
        using C = std::decay_t<decltype(config)>;
        if constexpr (std::is_same_v<C, drivers::SimBaseConfig>) {
          return std::make_unique<drivers::SimBase>(config);
        } else if constexpr (std::is_same_v<C, drivers::OdriveCanConfig>) {
          return std::make_unique<drivers::OdriveCanDrive>(config);
        } else if constexpr (std::is_same_v<C, drivers::ArduinoBridgeConfig>) {
          return std::make_unique<drivers::ArduinoBridgeDrive>(config);
        } else if constexpr (std::is_same_v<C, drivers::Ros2DriveConfig>) {
          return std::make_unique<drivers::Ros2Drive>(config);
        } else {
          return std::make_unique<drivers::RoboClawDrive>(config);
        }
      },
      section.drive);
  return std::make_unique<drivers::MobileBase>(std::move(drive), section.stage);
}

}  // namespace flowsteer::config
