#include "flowsteer/pipeline/run_recorder.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include "flowsteer/base/command.hpp"
#include "flowsteer/base/output_files.hpp"
#include "flowsteer/pipeline/brain.hpp"
#include "flowsteer/recording/foxglove_messages.hpp"

namespace flowsteer::pipeline {

namespace ros2 = recording::ros2;
namespace fox = recording::foxglove;

namespace {

constexpr const char* kStepSchemaName = "flowsteer.AgentStep";

// The JSON Schema of the step message (step_json), for the MCAP Schema record.
const std::string& step_schema() {
  static const std::string schema = R"({"title":"flowsteer.AgentStep",
"description":"One control step of an agent: its command, its cost terms and what it saw",
"type":"object","properties":{
 "timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},
 "flow_status":{"type":"string"},"blind":{"type":"boolean"},
 "command":{"type":"object","properties":{"accel_mps2":{"type":"number"},
  "turn_rate":{"type":"number","description":"rad/s about the camera's y axis, positive right"}}},
 "cost_total":{"type":["number","null"]},
 "terms":{"type":"object","additionalProperties":{"type":["number","null"]},
  "description":"each cost term's unweighted cost, by name"},
 "min_ttc_s":{"type":["number","null"]},
 "objects":{"type":"array","items":{"type":"object","properties":{
  "label":{"type":"integer"},"status":{"type":"string"},"kind":{"type":"string"},
  "centre_x":{"type":"number"},"centre_y":{"type":"number"},"width":{"type":"number"},
  "foe_x":{"type":["number","null"]},"foe_y":{"type":["number","null"]},
  "ttc_s":{"type":["number","null"]},"pixels":{"type":"integer"}}}}},
"required":["timestamp","flow_status","blind","command","cost_total","terms","objects"]})";
  return schema;
}

std::string number(double value) {
  return base::json_number(value, base::Digits::exact);
}

std::string step_json(std::uint64_t t_ns, const Brain& brain) {
  const servo::ControlOutput& output = brain.output();
  std::string out = "{\"timestamp\":" + fox::json_time(t_ns) +
                    ",\"flow_status\":" + base::json_string(servo::to_string(brain.flow_status())) +
                    ",\"blind\":" + (brain.blind() ? "true" : "false") +
                    ",\"command\":{\"accel_mps2\":" + number(output.command.accel_mps2) +
                    ",\"turn_rate\":" + number(output.command.turn_rate) +
                    "},\"cost_total\":" + number(output.cost) + ",\"terms\":{";
  for (std::size_t k = 0; k < output.terms.size(); ++k) {
    out += (k > 0 ? std::string(",") : std::string()) + base::json_string(output.terms[k].name) +
           ":" + number(output.terms[k].gradient.cost);
  }
  out += "},\"objects\":[";
  const auto objects = brain.objects();
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const servo::ObjectFeatures& o = objects[i];
    out += (i > 0 ? std::string(",") : std::string()) + "{\"label\":" + std::to_string(o.label) +
           ",\"status\":" + base::json_string(servo::to_string(o.status)) +
           ",\"kind\":" + base::json_string(servo::to_string(o.kind)) +
           ",\"centre_x\":" + number(o.centre.x()) + ",\"centre_y\":" + number(o.centre.y()) +
           ",\"width\":" + number(o.width) + ",\"foe_x\":" + number(o.foe.x()) +
           ",\"foe_y\":" + number(o.foe.y()) + ",\"ttc_s\":" + number(o.ttc_s) +
           ",\"pixels\":" + std::to_string(o.pixel_count) + "}";
  }
  return out + "],\"min_ttc_s\":" + number(brain.min_ttc_s()) + "}";
}

fox::Color status_color(servo::MotionStatus status) {
  switch (status) {
    case servo::MotionStatus::approaching:
      return {0.9, 0.2, 0.1, 1.0};
    case servo::MotionStatus::receding:
      return {0.2, 0.8, 0.3, 1.0};
    default:
      return {0.7, 0.7, 0.7, 1.0};
  }
}

// Each object as a line across its extent at its centre's height, its FOE as a circle and its
// TTC as a text, in pixels: what the overlay draws, for a viewer to draw on the image.
fox::ImageAnnotations annotations(const Brain& brain, const base::CameraIntrinsics& k) {
  fox::ImageAnnotations a;
  const auto col = [&](double x) { return k.cx_px + k.fx_px * x; };
  const auto row = [&](double y) { return k.cy_px + k.fy_px * y; };
  for (const servo::ObjectFeatures& o : brain.objects()) {
    const fox::Color color = status_color(o.status);
    const double y = row(o.centre.y());
    a.polylines.push_back({{{col(o.min_x), y}, {col(o.max_x), y}}, false, 2.0, color});
    if (o.has_foe() && std::isfinite(o.foe.x()) && std::isfinite(o.foe.y())) {
      a.circles.push_back({{col(o.foe.x()), row(o.foe.y())}, 8.0, 2.0, color});
    }
    if (std::isfinite(o.ttc_s)) {
      char text[32];
      std::snprintf(text, sizeof text, "%.1f s", o.ttc_s);
      a.texts.push_back({{col(o.centre.x()), y - 4.0}, text, 12.0, color});
    }
  }
  return a;
}

ros2::CameraInfo camera_info(const base::CameraIntrinsics& k, ros2::Header header) {
  ros2::CameraInfo info;
  info.header = std::move(header);
  info.width = static_cast<std::uint32_t>(k.width_px);
  info.height = static_cast<std::uint32_t>(k.height_px);
  info.d.assign(5, 0.0);  // the images are undistorted
  info.k = {k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0};
  info.r = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.p = {k.fx_px, 0.0, k.cx_px, 0.0, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

}  // namespace

RunRecorder::RunRecorder(const RecordingOptions& options, std::string clock,
                         std::string fixed_frame)
    : writer_(options.path, recording::McapWriterOptions{}),
      options_(options),
      clock_(std::move(clock)),
      fixed_frame_(std::move(fixed_frame)) {
  tf_ = ros2_channel<ros2::TFMessage>("/tf");
  tf_static_ = ros2_channel<ros2::TFMessage>("/tf_static");
}

std::vector<std::string> RunRecorder::ros_names(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::string name;
    for (const unsigned char c : names[i]) {
      const char kept = std::isalnum(c) ? static_cast<char>(c) : '_';
      if (kept != '_' || (!name.empty() && name.back() != '_')) {
        name += kept;
      }
    }
    while (!name.empty() && name.back() == '_') {
      name.pop_back();
    }
    if (name.empty() || std::isdigit(static_cast<unsigned char>(name.front()))) {
      name.insert(name.begin(), 'a');
    }
    if (std::find(out.begin(), out.end(), name) != out.end()) {
      name += '_';
      name += std::to_string(i);
    }
    out.push_back(std::move(name));
  }
  return out;
}

std::string RunRecorder::frame(const Agent& agent, const char* frame) const {
  return agent.ns.empty() ? frame : agent.ns + "/" + frame;
}

template <typename Message>
std::uint16_t RunRecorder::ros2_channel(const std::string& topic) {
  using Type = ros2::MessageType<Message>;
  auto schema = std::find_if(schemas_.begin(), schemas_.end(),
                             [](const auto& s) { return s.first == Type::name(); });
  if (schema == schemas_.end()) {
    schemas_.emplace_back(Type::name(),
                          writer_.add_schema(Type::name(), "ros2msg", Type::schema()));
    schema = schemas_.end() - 1;
  }
  return writer_.add_channel(topic, "cdr", schema->second);
}

std::uint16_t RunRecorder::json_channel(const std::string& topic, const char* schema_name,
                                        const std::string& schema_text) {
  auto schema = std::find_if(schemas_.begin(), schemas_.end(),
                             [&](const auto& s) { return s.first == schema_name; });
  if (schema == schemas_.end()) {
    schemas_.emplace_back(schema_name, writer_.add_schema(schema_name, "jsonschema", schema_text));
    schema = schemas_.end() - 1;
  }
  return writer_.add_channel(topic, "json", schema->second);
}

void RunRecorder::write_json(std::uint16_t channel, std::uint64_t t_ns, const std::string& json) {
  writer_.write(channel, t_ns, {reinterpret_cast<const std::uint8_t*>(json.data()), json.size()});
}

template <typename Message>
void RunRecorder::write(std::uint16_t channel, std::uint64_t t_ns, const Message& message) {
  ros2::MessageType<Message>::encode(message, bytes_);
  writer_.write(channel, t_ns, bytes_);
}

std::size_t RunRecorder::add_agent(const std::string& ns, const base::CameraIntrinsics& intrinsics,
                                   const std::optional<base::CameraMount>& mount) {
  const std::string prefix = ns.empty() ? "" : "/" + ns;
  Agent agent{ns, intrinsics, mount, 0, 0, 0, 0, 0, 0, std::nullopt, 0};
  agent.cmd_vel = ros2_channel<ros2::Twist>(prefix + "/cmd_vel");
  agent.odom = ros2_channel<ros2::Odometry>(prefix + "/odom");
  agent.image = ros2_channel<ros2::CompressedImage>(prefix + "/camera/image/compressed");
  agent.camera_info = ros2_channel<ros2::CameraInfo>(prefix + "/camera/camera_info");
  agent.annotations = json_channel(prefix + "/camera/annotations", fox::kImageAnnotations,
                                   fox::image_annotations_schema());
  agent.step = json_channel(ns.empty() ? "/flowsteer/step" : prefix + "/step", kStepSchemaName,
                            step_schema());
  agents_.push_back(std::move(agent));
  return agents_.size() - 1;
}

void RunRecorder::write_mounts(std::uint64_t t_ns) {
  ros2::TFMessage tf;
  for (const Agent& agent : agents_) {
    if (!agent.mount) {
      continue;
    }
    const Eigen::Quaterniond q(agent.mount->camera_to_body());
    tf.transforms.push_back({{ros2::Time::from_ns(t_ns), frame(agent, "base_link")},
                             frame(agent, "camera_optical"),
                             {0.0, 0.0, agent.mount->height_m},
                             {q.x(), q.y(), q.z(), q.w()}});
  }
  write(tf_static_, t_ns, tf);
}

void RunRecorder::command(std::size_t agent, std::uint64_t t_ns, double speed_mps,
                          double turn_rate) {
  write(agents_.at(agent).cmd_vel, t_ns,
        ros2::Twist{{speed_mps, 0.0, 0.0}, {0.0, 0.0, base::yaw_rate_of(turn_rate)}});
}

void RunRecorder::odometry(std::size_t agent_index, std::uint64_t t_ns, double x_m, double y_m,
                           double yaw_rad, double speed_mps, double turn_rate) {
  Agent& agent = agents_.at(agent_index);
  ros2::Odometry odom;
  odom.header = {ros2::Time::from_ns(t_ns), fixed_frame_};
  odom.child_frame_id = frame(agent, "base_link");
  odom.pose.position = {x_m, y_m, 0.0};
  odom.pose.orientation = ros2::Quaternion::from_yaw(yaw_rad);
  odom.twist = {{speed_mps, 0.0, 0.0}, {0.0, 0.0, base::yaw_rate_of(turn_rate)}};
  write(agent.odom, t_ns, odom);
  agent.pose = ros2::TransformStamped{odom.header, odom.child_frame_id, odom.pose.position,
                                      odom.pose.orientation};
}

void RunRecorder::write_transforms(std::uint64_t t_ns) {
  ros2::TFMessage tf;
  for (const Agent& agent : agents_) {
    if (agent.pose) {
      tf.transforms.push_back(*agent.pose);
      tf.transforms.back().header.stamp = ros2::Time::from_ns(t_ns);
    }
  }
  write(tf_, t_ns, tf);
}

void RunRecorder::percept(std::size_t agent_index, std::uint64_t t_ns, const Brain& brain,
                          const cv::Mat& image) {
  Agent& agent = agents_.at(agent_index);
  if (options_.images_every > 0 && agent.percepts % options_.images_every == 0) {
    write_image(agent, t_ns, image);
  }
  ++agent.percepts;
  const std::string annotations_text =
      fox::image_annotations_json(t_ns, annotations(brain, agent.intrinsics));
  writer_.write(
      agent.annotations, t_ns,
      {reinterpret_cast<const std::uint8_t*>(annotations_text.data()), annotations_text.size()});
  const std::string step_text = step_json(t_ns, brain);
  writer_.write(agent.step, t_ns,
                {reinterpret_cast<const std::uint8_t*>(step_text.data()), step_text.size()});
}

// PNG: lossless, so that a replay of the recording sees the pixels the agent saw.
void RunRecorder::write_image(const Agent& agent, std::uint64_t t_ns, const cv::Mat& image) {
  const ros2::Header header{ros2::Time::from_ns(t_ns), frame(agent, "camera_optical")};
  ros2::CompressedImage compressed;
  compressed.header = header;
  compressed.format = "png";
  cv::imencode(".png", image, compressed.data);
  write(agent.image, t_ns, compressed);
  write(agent.camera_info, t_ns, camera_info(agent.intrinsics, header));
}

void RunRecorder::finish(std::vector<std::pair<std::string, std::string>> metadata) {
  std::string namespaces = "[";
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    namespaces += i > 0 ? "," : "";
    namespaces += base::json_string(agents_[i].ns);
  }
  metadata.insert(metadata.begin(), {{"version", recording::flowsteer_version()},
                                     {"clock", clock_},
                                     {"fixed_frame", fixed_frame_},
                                     {"agents", namespaces + "]"}});
  writer_.add_metadata("flowsteer", metadata);
  writer_.finish();
}

}  // namespace flowsteer::pipeline
