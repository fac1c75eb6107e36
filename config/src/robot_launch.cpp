#include "flowsteer/config/robot_launch.hpp"

#include <filesystem>
#include <numbers>

#include "drive_reader.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "flowsteer/calibration/camera_info.hpp"
#include "flowsteer/calibration/camera_mount.hpp"
#include "flowsteer/config/controller_reader.hpp"
#include "flowsteer/config/field_bounds.hpp"
#include "flowsteer/ros2_dds/topics.hpp"
#include "ros2_reader.hpp"

namespace flowsteer::config {
namespace {

namespace fs = std::filesystem;

std::string resolve(const std::string& path, const std::string& base_dir) {
  const fs::path p(path);
  return p.is_absolute() || base_dir.empty() ? path : (fs::path(base_dir) / p).string();
}

// Size and rate shared by the camera types.
template <typename Options>
void read_size_and_rate(const base::YamlReader& r, const YAML::Node& node, const std::string& field,
                        Options& o) {
  if (node["width_px"]) {
    o.width_px = r.bounded_integer(node["width_px"], field + ".width_px");
  }
  if (node["height_px"]) {
    o.height_px = r.bounded_integer(node["height_px"], field + ".height_px");
  }
  o.frame_rate_hz = r.bounded(node, field, "frame_rate_hz", o.frame_rate_hz);
  if (node["buffer_count"]) {
    o.buffer_count = r.bounded_integer(node["buffer_count"], field + ".buffer_count");
  }
}

// A ROS 2 camera driver's topics. Its lens is CameraInfo's when a camera_info topic is named,
// else camera.calibration's or camera.horizontal_fov_rad's, as for the other cameras.
camera_io::Ros2CameraOptions read_ros2_camera(const base::YamlReader& r, const YAML::Node& camera,
                                              const YAML::Node& settings, const std::string& field,
                                              const camera_io::LensOptions& lens) {
  r.only_keys(settings, field, {"domain_id", "image", "camera_info", "connect_timeout_s"});
  camera_io::Ros2CameraOptions o;
  o.domain_id = read_ros2_domain_id(r, settings, field);
  const std::string image_field = field + ".image";
  const YAML::Node image = settings["image"];
  if (image) {
    r.only_keys(image, image_field, {"topic", "type", "encoding"});
  }
  const Ros2Topic topic =
      read_ros2_topic(r, image, image_field,
                      {o.image_topic, std::string(camera_io::ros2_image_type_name(o.image_type))},
                      {"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"});
  o.image_topic = topic.topic;
  o.image_type = *camera_io::ros2_image_type_from_name(topic.type);
  if (image && image["encoding"]) {
    if (o.image_type != camera_io::Ros2ImageType::image) {
      r.fail(image["encoding"], image_field + ".encoding",
             "only a " + camera_io::ros2_image_type_name(camera_io::Ros2ImageType::image) +
                 " has an encoding");
    }
    o.encoding = r.text(image, image_field, "encoding", "", true);
    if (!camera_io::is_readable_ros2_image_encoding(o.encoding)) {
      r.fail(image["encoding"], image_field + ".encoding",
             "'" + o.encoding + "' is not an encoding flowsteer reads (" +
                 camera_io::ros2_image_encoding_names() + ")");
    }
  }
  if (const YAML::Node info = settings["camera_info"]) {
    for (const char* lens_field : {"calibration", "horizontal_fov_rad"}) {
      if (camera[lens_field]) {
        r.fail(info, field + ".camera_info",
               std::string("give camera.") + lens_field + " or a camera_info topic, not both");
      }
    }
    r.only_keys(info, field + ".camera_info", {"topic", "type"});
    const std::string camera_info = ros2_dds::ros2_type_name<recording::ros2::CameraInfo>();
    o.camera_info_topic = read_ros2_topic(r, info, field + ".camera_info",
                                          {"/camera/camera_info", camera_info}, {camera_info})
                              .topic;
  }
  o.connect_timeout_s = r.bounded(settings, field, "connect_timeout_s", o.connect_timeout_s);
  o.lens = lens;
  return o;
}

CameraSection read_camera(const base::YamlReader& r, const YAML::Node& camera,
                          const std::string& base_dir, std::vector<std::string>& warnings) {
  r.only_keys(camera, "camera",
              {"type", "timeout_s", "calibration", "horizontal_fov_rad", "v4l2", "libcamera",
               "replay", "ros2"});
  const std::string type =
      r.word(camera, "camera", "type", {"v4l2", "libcamera", "replay", "ros2"}, "");
  if (type.empty()) {
    r.fail(camera, "camera.type", "missing: v4l2, libcamera, replay or ros2");
  }
  for (const char* other : {"v4l2", "libcamera", "replay", "ros2"}) {
    if (camera[other] && type != other) {
      r.fail(camera[other], std::string("camera.") + other,
             "settings for another camera than type '" + type + "'");
    }
  }
  CameraSection s;
  s.timeout_s = r.bounded(camera, "camera", "timeout_s", s.timeout_s);
  camera_io::LensOptions lens;
  lens.horizontal_fov_rad =
      r.bounded(camera, "camera", "horizontal_fov_rad", lens.horizontal_fov_rad);
  if (camera["calibration"]) {
    s.calibration_file = resolve(r.text(camera, "camera", "calibration", "", true), base_dir);
    // The reader's base::ConfigError names the calibration file's own line and field.
    lens.model = calibration::read_camera_info(s.calibration_file, warnings).model;
  }

  const YAML::Node settings = camera[type] ? camera[type] : YAML::Node(YAML::NodeType::Map);
  const std::string field = "camera." + type;
  if (type == "v4l2") {
    r.only_keys(
        settings, field,
        {"device", "width_px", "height_px", "frame_rate_hz", "pixel_format", "buffer_count"});
    camera_io::V4l2Options o;
    o.device = r.text(settings, field, "device", o.device, true);
    read_size_and_rate(r, settings, field, o);
    o.format = *camera_io::pixel_format_from_name(
        r.word(settings, field, "pixel_format", {"YUYV", "MJPG", "MJPEG", "GREY"}, "YUYV"));
    o.lens = lens;
    s.source = o;
  } else if (type == "libcamera") {
    r.only_keys(settings, field,
                {"camera_id", "width_px", "height_px", "frame_rate_hz", "buffer_count"});
    camera_io::LibcameraOptions o;
    o.camera_id = r.text(settings, field, "camera_id", "", true);
    read_size_and_rate(r, settings, field, o);
    o.lens = lens;
    s.source = o;
  } else if (type == "ros2") {
    s.source = read_ros2_camera(r, camera, settings, field, lens);
  } else {
    r.only_keys(settings, field, {"path", "frame_rate_hz"});
    camera_io::ReplayOptions o;
    o.path = r.text(settings, field, "path", "", true);
    if (o.path.empty()) {
      r.fail(settings, field + ".path", "missing: the video file or image pattern to replay");
    }
    o.path = resolve(o.path, base_dir);
    o.frame_rate_hz = r.bounded(settings, field, "frame_rate_hz", 0.0);
    o.lens = lens;
    s.source = o;
  }
  // A calibration is for one image size; a camera asked for another would fail only when it
  // opens, so say it here, at the line that asks.
  if (lens.model && type != "replay" && type != "ros2") {
    const auto check = [&](int width, int height) {
      if (width != lens.model->width_px || height != lens.model->height_px) {
        r.fail(camera["calibration"], "camera.calibration",
               s.calibration_file + " is for " + std::to_string(lens.model->width_px) + "x" +
                   std::to_string(lens.model->height_px) + " images, the camera is set to " +
                   std::to_string(width) + "x" + std::to_string(height));
      }
    };
    std::visit(
        [&](const auto& o) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(o)>, camera_io::ReplayOptions>) {
            if constexpr (!std::is_same_v<std::decay_t<decltype(o)>,
                                          camera_io::Ros2CameraOptions>) {
              check(o.width_px, o.height_px);
            }
          }
        },
        s.source);
  }
  return s;
}

PerceptionSection read_robot_perception(const base::YamlReader& r, const YAML::Node& node,
                                        const std::string& base_dir) {
  PerceptionSection p;
  if (!node) {
    return p;
  }
  r.only_keys(node, "perception",
              {"flow", "segmentation", "dark_regions", "obstacle_memory", "mount", "height_m",
               "pitch_deg"});
  servo::PerceptionConfig methods{p.flow, p.segmentation};
  methods = read_perception(r, node, "perception", methods);
  if (methods.flow == servo::FlowMethod::synthetic) {
    r.fail(
        node["flow"], "perception.flow",
        "synthetic flow needs a simulator; a camera needs one of " + numerical_flow_method_names());
  }
  if (methods.segmentation == servo::SegmentationMethod::semantic) {
    r.fail(node["segmentation"], "perception.segmentation",
           "semantic segmentation needs a simulator's object ids; a camera needs flow_graph or "
           "flow_graph_fast");
  }
  p.flow = methods.flow;
  p.segmentation = methods.segmentation;
  p.obstacle_memory = methods.obstacle_memory;
  p.dark_regions = r.boolean(node, "perception", "dark_regions", p.dark_regions);
  if (node["mount"] && (node["height_m"] || node["pitch_deg"])) {
    r.fail(node["mount"], "perception.mount",
           "give a camera mount file or height_m and pitch_deg, not both");
  }
  if (node["mount"]) {
    p.mount_file = resolve(r.text(node, "perception", "mount", "", true), base_dir);
    // The reader's base::ConfigError names the mount file's own line and field.
    p.mount = calibration::read_camera_mount(p.mount_file).mount;
  } else if (node["height_m"] || node["pitch_deg"]) {
    if (!node["height_m"]) {
      r.fail(node, "perception.height_m", "missing: the camera's height above the floor");
    }
    base::CameraMount mount;
    mount.height_m = r.bounded(node, "perception", "height_m", 0.0);
    mount.pitch_rad = r.bounded(node, "perception", "pitch_deg", 0.0) * std::numbers::pi / 180.0;
    p.mount = mount;
  }
  return p;
}

ControllerSection read_robot_controller(const base::YamlReader& r, const YAML::Node& node) {
  ControllerSection c;
  if (!node) {
    return c;
  }
  // Goal reaching on the flow's features only: following needs a leader's id and the other
  // steering models need a simulator.
  r.only_keys(node, "controller",
              {"law", "alpha", "beta", "gamma", "delta", "braking", "anticipation", "lambda",
               "max_accel_mps2", "max_turn_rate", "max_speed_ratio", "use_depth",
               "clearance_margin_m", "preferred_speed_mps", "robot_width_m"});
  c.spec = read_controller(r, node, "controller", c.spec);
  c.preferred_speed_mps =
      r.bounded(node, "controller", "preferred_speed_mps", c.preferred_speed_mps);
  c.robot_width_m = r.bounded(node, "controller", "robot_width_m", c.robot_width_m);
  return c;
}

}  // namespace

RobotLaunch parse_robot_launch(const std::string& yaml_text, const std::string& source_name,
                               const std::string& base_dir) {
  const base::YamlReader r(source_name, robot_launch_bounds());
  const YAML::Node root =
      base::load_yaml_map(yaml_text, source_name, "camera, drive and goal",
                          {"camera", "drive", "goal", "perception", "controller"});
  RobotLaunch launch;
  if (!root["camera"]) {
    throw base::ConfigError(source_name, 1, 1, "camera", "missing: the launch file has no camera");
  }
  launch.camera = read_camera(r, root["camera"], base_dir, launch.warnings);
  if (root["drive"]) {
    launch.drive = read_drive(r, root["drive"]);
    if (1.0 / launch.drive->loop_rate_hz >= launch.camera.timeout_s) {
      r.fail(root["drive"]["loop_rate_hz"] ? root["drive"]["loop_rate_hz"] : root["drive"],
             "drive.loop_rate_hz", "one loop period must be shorter than camera.timeout_s");
    }
  }
  if (const YAML::Node goal = root["goal"]) {
    r.only_keys(goal, "goal", {"bearing_rad", "distance_m"});
    GoalSection g;
    g.bearing_rad = r.bounded(goal, "goal", "bearing_rad", 0.0);
    if (!goal["distance_m"]) {
      r.fail(goal, "goal.distance_m", "missing: how far the goal is");
    }
    g.distance_m = r.bounded(goal, "goal", "distance_m", 0.0);
    launch.goal = g;
  }
  launch.perception = read_robot_perception(r, root["perception"], base_dir);
  launch.controller = read_robot_controller(r, root["controller"]);
  if (launch.drive && !launch.perception.mount) {
    r.fail(root["perception"] ? root["perception"] : root, "perception.mount",
           "missing: with a drive, the flat-ground test needs the camera mount (mount: FILE, or "
           "height_m and pitch_deg)");
  }
  if (launch.perception.dark_regions !=
      (servo::navigation_weights(launch.controller.spec).delta > 0.0)) {
    r.fail(root["perception"] && root["perception"]["dark_regions"]
               ? root["perception"]["dark_regions"]
               : (root["controller"] ? root["controller"] : root),
           "perception.dark_regions",
           launch.perception.dark_regions
               ? "true needs controller.delta > 0 to weigh the dark regions"
               : "controller.delta > 0 weighs dark regions: set perception.dark_regions: true");
  }
  return launch;
}

RobotLaunch read_robot_launch(const std::string& path) {
  const std::string text = base::read_text_file(path, "launch file");
  return parse_robot_launch(text, path, fs::path(path).parent_path().string());
}

std::string numerical_flow_method_names() {
  std::string names;
  for (const servo::FlowMethod method : servo::numerical_flow_methods()) {
    names += (names.empty() ? "" : ", ") + std::string(servo::to_string(method));
  }
  return names;
}

std::unique_ptr<camera_io::FrameSource> make_camera(const CameraSection& section) {
  return std::visit(
      [](const auto& o) -> std::unique_ptr<camera_io::FrameSource> {
        using O = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<O, camera_io::V4l2Options>) {
          return std::make_unique<camera_io::V4l2Camera>(o);
        } else if constexpr (std::is_same_v<O, camera_io::ReplayOptions>) {
          return std::make_unique<camera_io::ReplaySource>(o);
        } else if constexpr (std::is_same_v<O, camera_io::Ros2CameraOptions>) {
          return std::make_unique<camera_io::Ros2Camera>(o);
        } else {
#ifdef FLOWSTEER_HAVE_LIBCAMERA
          return std::make_unique<camera_io::LibcameraCamera>(o);
#else
          throw std::runtime_error(
              "camera type libcamera: this flowsteer was built without libcamera "
              "(install libcamera-dev and build again)");
#endif
        }
      },
      section.source);
}

std::string describe_camera(const CameraSection& section) {
  return std::visit(
      [](const auto& o) -> std::string {
        using O = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<O, camera_io::V4l2Options>) {
          return "v4l2 camera " + o.device;
        } else if constexpr (std::is_same_v<O, camera_io::ReplayOptions>) {
          return "replay " + o.path;
        } else if constexpr (std::is_same_v<O, camera_io::Ros2CameraOptions>) {
          return "ros2 camera " + o.image_topic + " (domain " + std::to_string(o.domain_id) + ")";
        } else {
          return "libcamera camera " + (o.camera_id.empty() ? std::string("(first)") : o.camera_id);
        }
      },
      section.source);
}

}  // namespace flowsteer::config
