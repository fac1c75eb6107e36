#include "flowsteer/launch/robot_launch.hpp"

#include <cmath>
#include <filesystem>
#include <numbers>

#include "flowsteer/calibration/camera_info.hpp"
#include "yaml_reader.hpp"

namespace flowsteer::launch {
namespace {

namespace fs = std::filesystem;

std::string text(const YamlReader& r, const YAML::Node& map, const std::string& field,
                 const char* key, const std::string& fallback) {
  const YAML::Node node = map[key];
  if (!node) {
    return fallback;
  }
  if (!node.IsScalar() || node.Scalar().empty()) {
    r.fail(node, YamlReader::join(field, key), "expected a non-empty text");
  }
  return node.Scalar();
}

std::string resolve(const std::string& path, const std::string& base_dir) {
  const fs::path p(path);
  return p.is_absolute() || base_dir.empty() ? path : (fs::path(base_dir) / p).string();
}

// Size and rate shared by the camera types.
template <typename Options>
void read_size_and_rate(const YamlReader& r, const YAML::Node& node, const std::string& field,
                        Options& o) {
  if (node["width_px"]) {
    o.width_px = r.integer(node["width_px"], field + ".width_px", 1);
  }
  if (node["height_px"]) {
    o.height_px = r.integer(node["height_px"], field + ".height_px", 1);
  }
  o.frame_rate_hz = r.non_negative(node, field, "frame_rate_hz", o.frame_rate_hz);
  if (node["buffer_count"]) {
    o.buffer_count = r.integer(node["buffer_count"], field + ".buffer_count", 2);
  }
}

CameraSection read_camera(const YamlReader& r, const YAML::Node& camera,
                          const std::string& base_dir, std::vector<std::string>& warnings) {
  r.only_keys(
      camera, "camera",
      {"type", "timeout_s", "calibration", "horizontal_fov_rad", "v4l2", "libcamera", "replay"});
  const std::string type = r.word(camera, "camera", "type", {"v4l2", "libcamera", "replay"}, "");
  if (type.empty()) {
    r.fail(camera, "camera.type", "missing: v4l2, libcamera or replay");
  }
  for (const char* other : {"v4l2", "libcamera", "replay"}) {
    if (camera[other] && type != other) {
      r.fail(camera[other], std::string("camera.") + other,
             "settings for another camera than type '" + type + "'");
    }
  }
  CameraSection s;
  s.timeout_s = r.positive(camera, "camera", "timeout_s", s.timeout_s);
  camera_io::LensOptions lens;
  lens.horizontal_fov_rad =
      r.positive(camera, "camera", "horizontal_fov_rad", lens.horizontal_fov_rad);
  if (lens.horizontal_fov_rad >= std::numbers::pi) {
    r.fail(camera["horizontal_fov_rad"], "camera.horizontal_fov_rad", "must be below pi");
  }
  if (camera["calibration"]) {
    s.calibration_file = resolve(text(r, camera, "camera", "calibration", ""), base_dir);
    // The reader's ConfigError names the calibration file's own line and field.
    lens.model = calibration::read_camera_info(s.calibration_file, warnings).model;
  }

  const YAML::Node settings = camera[type] ? camera[type] : YAML::Node(YAML::NodeType::Map);
  const std::string field = "camera." + type;
  if (type == "v4l2") {
    r.only_keys(
        settings, field,
        {"device", "width_px", "height_px", "frame_rate_hz", "pixel_format", "buffer_count"});
    camera_io::V4l2Options o;
    o.device = text(r, settings, field, "device", o.device);
    read_size_and_rate(r, settings, field, o);
    o.format = *camera_io::pixel_format_from_name(
        r.word(settings, field, "pixel_format", {"YUYV", "MJPG", "MJPEG", "GREY"}, "YUYV"));
    o.lens = lens;
    s.source = o;
  } else if (type == "libcamera") {
    r.only_keys(settings, field,
                {"camera_id", "width_px", "height_px", "frame_rate_hz", "buffer_count"});
    camera_io::LibcameraOptions o;
    o.camera_id = text(r, settings, field, "camera_id", "");
    read_size_and_rate(r, settings, field, o);
    o.lens = lens;
    s.source = o;
  } else {
    r.only_keys(settings, field, {"path", "frame_rate_hz"});
    camera_io::ReplayOptions o;
    o.path = text(r, settings, field, "path", "");
    if (o.path.empty()) {
      r.fail(settings, field + ".path", "missing: the video file or image pattern to replay");
    }
    o.path = resolve(o.path, base_dir);
    o.frame_rate_hz = r.non_negative(settings, field, "frame_rate_hz", 0.0);
    o.lens = lens;
    s.source = o;
  }
  // A calibration is for one image size; a camera asked for another would fail only when it
  // opens, so say it here, at the line that asks.
  if (lens.model && type != "replay") {
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
            check(o.width_px, o.height_px);
          }
        },
        s.source);
  }
  return s;
}

}  // namespace

RobotLaunch parse_robot_launch(const std::string& yaml_text, const std::string& source_name,
                               const std::string& base_dir) {
  const YamlReader r(source_name);
  const YAML::Node root = load_yaml(yaml_text, source_name);
  if (!root.IsMap()) {
    throw ConfigError(source_name, 1, 1, "", "expected a mapping with camera, drive and goal");
  }
  r.only_keys(root, "", {"camera", "drive", "goal"});
  RobotLaunch launch;
  if (!root["camera"]) {
    throw ConfigError(source_name, 1, 1, "camera", "missing: the launch file has no camera");
  }
  launch.camera = read_camera(r, root["camera"], base_dir, launch.warnings);
  if (root["drive"]) {
    launch.drive = parse_drive_section(yaml_text, source_name);
    if (1.0 / launch.drive->loop_rate_hz >= launch.camera.timeout_s) {
      r.fail(root["drive"]["loop_rate_hz"] ? root["drive"]["loop_rate_hz"] : root["drive"],
             "drive.loop_rate_hz", "one loop period must be shorter than camera.timeout_s");
    }
  }
  if (const YAML::Node goal = root["goal"]) {
    r.only_keys(goal, "goal", {"bearing_rad", "distance_m"});
    GoalSection g;
    g.bearing_rad = r.number(goal, "goal", "bearing_rad", 0.0);
    if (std::abs(g.bearing_rad) > std::numbers::pi) {
      r.fail(goal["bearing_rad"], "goal.bearing_rad", "must be within [-pi, pi]");
    }
    if (!goal["distance_m"]) {
      r.fail(goal, "goal.distance_m", "missing: how far the goal is");
    }
    g.distance_m = r.positive(goal, "goal", "distance_m", 0.0);
    launch.goal = g;
  }
  return launch;
}

RobotLaunch read_robot_launch(const std::string& path) {
  const std::string text = read_text_file(path, "launch file");
  return parse_robot_launch(text, path, fs::path(path).parent_path().string());
}

std::unique_ptr<camera_io::FrameSource> make_camera(const CameraSection& section) {
  return std::visit(
      [](const auto& o) -> std::unique_ptr<camera_io::FrameSource> {
        using O = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<O, camera_io::V4l2Options>) {
          return std::make_unique<camera_io::V4l2Camera>(o);
        } else if constexpr (std::is_same_v<O, camera_io::ReplayOptions>) {
          return std::make_unique<camera_io::ReplaySource>(o);
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
        } else {
          return "libcamera camera " + (o.camera_id.empty() ? std::string("(first)") : o.camera_id);
        }
      },
      section.source);
}

}  // namespace flowsteer::launch
