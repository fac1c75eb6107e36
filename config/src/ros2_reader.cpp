#include "ros2_reader.hpp"

#include "flowsteer/ros2_dds/participant.hpp"

namespace flowsteer::config {

int read_ros2_domain_id(const base::YamlReader& r, const YAML::Node& node,
                        const std::string& field) {
  if (node["domain_id"]) {
    return r.bounded_integer(node["domain_id"], field + ".domain_id");
  }
  try {
    return ros2_dds::domain_id_from_environment();
  } catch (const ros2_dds::DdsError& error) {
    r.fail(node, field + ".domain_id", std::string("not given, and ") + error.what());
  }
}

Ros2Topic read_ros2_topic(const base::YamlReader& r, const YAML::Node& topic_node,
                          const std::string& topic_field, const Ros2Topic& defaults,
                          std::initializer_list<std::string> types) {
  if (!topic_node) {
    return defaults;
  }
  Ros2Topic t;
  t.topic = r.text(topic_node, topic_field, "topic", defaults.topic, true);
  if (const auto problem = ros2_dds::topic_name_problem(t.topic)) {
    r.fail(topic_node["topic"], topic_field + ".topic", "'" + t.topic + "': " + *problem);
  }
  const std::string type = r.text(topic_node, topic_field, "type", defaults.type, true);
  std::string accepted;
  for (const std::string& full : types) {
    // "pkg/msg/Type" or "pkg/Type"
    const std::string short_name = full.substr(0, full.find('/')) + full.substr(full.rfind('/'));
    if (type == full || type == short_name) {
      t.type = full;
      return t;
    }
    accepted += (accepted.empty() ? "" : ", ") + full;
  }
  r.fail(topic_node["type"], topic_field + ".type",
         "'" + type + "' is not a type flowsteer reads or writes here (" + accepted + ")");
}

}  // namespace flowsteer::config
