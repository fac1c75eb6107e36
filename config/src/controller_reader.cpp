#include "flowsteer/config/controller_reader.hpp"

#include <utility>

namespace flowsteer::config {

namespace {

// The names of servo's enums are string literals: null-terminated views.
const char* to_c_str(std::string_view literal) {
  return literal.data();
}

// The settings of type motion_energy; given with another type, they are a mistake.
void read_motion_energy(const base::YamlReader& r, const YAML::Node& node, const std::string& field,
                        servo::ControllerConfig& c) {
  if (c.model != servo::SteeringModel::motion_energy) {
    for (const char* key : {"mass_from", "flow_weight", "steer_gain", "goal_gain", "head_on_energy",
                            "head_on_balance", "danger_distance_m", "danger_fraction",
                            "corner_step", "corner_rise", "free_path_range_m"}) {
      if (node[key]) {
        r.fail(node[key], base::YamlReader::join(field, key),
               "only for type: motion_energy (this controller's type is " +
                   std::string(servo::to_string(c.model)) + ")");
      }
    }
    return;
  }
  servo::MotionEnergyOptions& m = c.motion_energy;
  c.mass_from = *servo::parse_mass_source(
      r.word(node, field, "mass_from", {"ids", "ground"}, to_c_str(servo::to_string(c.mass_from))));
  m.flow_weight = r.bounded(node, field, "flow_weight", m.flow_weight);
  m.steer_gain = r.bounded(node, field, "steer_gain", m.steer_gain);
  m.goal_gain = r.bounded(node, field, "goal_gain", m.goal_gain);
  m.head_on_energy = r.bounded(node, field, "head_on_energy", m.head_on_energy);
  m.head_on_balance = r.bounded(node, field, "head_on_balance", m.head_on_balance);
  m.danger_distance_m = r.bounded(node, field, "danger_distance_m", m.danger_distance_m);
  m.danger_fraction = r.bounded(node, field, "danger_fraction", m.danger_fraction);
  m.corner_step = r.bounded(node, field, "corner_step", m.corner_step);
  m.corner_rise = r.bounded(node, field, "corner_rise", m.corner_rise);
  m.free_path_range_m = r.bounded(node, field, "free_path_range_m", m.free_path_range_m);
}

}  // namespace

servo::ControllerConfig read_controller(const base::YamlReader& r, const YAML::Node& node,
                                        const std::string& field, servo::ControllerConfig c) {
  if (!node) {
    return c;
  }
  c.model = *servo::parse_steering_model(r.word(node, field, "type",
                                                {"vision", "geometric", "motion_energy"},
                                                to_c_str(servo::to_string(c.model))));
  c.kind = *servo::parse_navigation_kind(r.word(node, field, "kind", {"goal_reaching", "following"},
                                                to_c_str(servo::to_string(c.kind))));
  c.law = *servo::parse_navigation_law(r.word(
      node, field, "law", {"flowsteer", "cgf2019", "mig2019"}, to_c_str(servo::to_string(c.law))));
  for (auto [key, weight] :
       {std::pair{"alpha", &c.alpha}, std::pair{"beta", &c.beta}, std::pair{"gamma", &c.gamma},
        std::pair{"delta", &c.delta}, std::pair{"braking", &c.braking},
        std::pair{"anticipation", &c.anticipation}}) {
    if (node[key]) {
      *weight = r.bounded(node, field, key, 0.0);
    }
  }
  if (c.law != servo::NavigationLaw::flowsteer) {
    for (const char* key :
         {"braking", "anticipation", "follow_gap_m", "max_speed_ratio", "without"}) {
      if (node[key]) {
        r.fail(node[key], base::YamlReader::join(field, key),
               "only for law: flowsteer (this controller's law is " +
                   std::string(servo::to_string(c.law)) + ")");
      }
    }
  }
  if (const YAML::Node without = node["without"]) {
    const auto mechanism = servo::parse_law_mechanism(without.IsScalar() ? without.Scalar() : "");
    if (!mechanism) {
      r.fail(without, base::YamlReader::join(field, "without"),
             "expected one of " + servo::law_mechanism_names());
    }
    c.without = *mechanism;
  }
  if (node["follow_gap_m"]) {  // a robot's file has no row for it: it does not follow
    c.follow_gap_m = r.bounded(node, field, "follow_gap_m", c.follow_gap_m);
  }
  c.max_speed_ratio = r.bounded(node, field, "max_speed_ratio", c.max_speed_ratio);
  const servo::NavigationWeights weights = servo::navigation_weights(c);
  if (weights.delta > weights.gamma) {
    r.fail(node["delta"] ? node["delta"] : node, field + ".delta",
           "must not exceed gamma (MIG 2019: visible obstacles weigh at least as much)");
  }
  c.lambda = r.bounded(node, field, "lambda", c.lambda);
  c.max_accel_mps2 = r.bounded(node, field, "max_accel_mps2", c.max_accel_mps2);
  c.max_turn_rate = r.bounded(node, field, "max_turn_rate", c.max_turn_rate);
  c.use_depth = r.boolean(node, field, "use_depth", c.use_depth);
  c.clearance_margin_m = r.bounded(node, field, "clearance_margin_m", c.clearance_margin_m);
  read_motion_energy(r, node, field, c);
  return c;
}

servo::PerceptionConfig read_perception(const base::YamlReader& r, const YAML::Node& node,
                                        const std::string& field,
                                        servo::PerceptionConfig perception) {
  if (!node) {
    return perception;
  }
  if (const YAML::Node flow = node["flow"]) {
    const auto method = servo::parse_flow_method(flow.IsScalar() ? flow.Scalar() : "");
    if (!method) {
      r.fail(flow, field + ".flow", "expected one of " + servo::flow_method_names());
    }
    perception.flow = *method;
  }
  if (const YAML::Node segmentation = node["segmentation"]) {
    const auto method =
        servo::parse_segmentation_method(segmentation.IsScalar() ? segmentation.Scalar() : "");
    if (!method) {
      r.fail(segmentation, field + ".segmentation",
             "expected one of " + servo::segmentation_method_names());
    }
    perception.segmentation = *method;
  }
  if (const YAML::Node depth = node["depth"]) {
    const auto source = servo::parse_depth_source(depth.IsScalar() ? depth.Scalar() : "");
    if (!source) {
      r.fail(depth, field + ".depth", "expected one of " + servo::depth_source_names());
    }
    perception.depth = *source;
  }
  perception.obstacle_memory =
      r.boolean(node, field, "obstacle_memory", perception.obstacle_memory);
  return perception;
}

}  // namespace flowsteer::config
