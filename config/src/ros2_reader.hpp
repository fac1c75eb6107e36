#pragma once

#include <initializer_list>
#include <string>

#include "flowsteer/base/yaml_reader.hpp"

namespace flowsteer::config {

// `domain_id` of a launch file's ros2 mapping `node` (field e.g. "drive.ros2"): the file's, else
// ROS_DOMAIN_ID's as ROS 2 reads it, else 0. A bad ROS_DOMAIN_ID fails at the mapping, naming
// the variable and its value.
int read_ros2_domain_id(const base::YamlReader& r, const YAML::Node& node,
                        const std::string& field);

// A topic the launch file names: `topic` (a ROS 2 topic name) and `type`, one of `types`
// (ros2_dds::ros2_type_name's "pkg/msg/Type", also accepted as "pkg/Type"), as its full name.
struct Ros2Topic {
  std::string topic;
  std::string type;
};

// Reads `topic` and `type` of the mapping `node` (field e.g. "drive.ros2.cmd_vel"; the caller
// checks its keys); the defaults where it or they are absent.
Ros2Topic read_ros2_topic(const base::YamlReader& r, const YAML::Node& node,
                          const std::string& field, const Ros2Topic& defaults,
                          std::initializer_list<std::string> types);

}  // namespace flowsteer::config
