#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "flowsteer/camera_io/camera_model.hpp"

namespace flowsteer::calibration {

// A ROS camera_info calibration file (the YAML of camera_calibration_parsers): the camera model
// and, for stereo rigs, the rectification and projection of the rectified image.
struct CameraInfo {
  std::string camera_name;
  camera_io::CameraModel model;
  std::array<double, 9> rectification{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major 3x3
  std::array<double, 12> projection{};                             // row-major 3x4

  // A monocular camera's camera_info: identity rectification, projection [K | 0].
  static CameraInfo monocular(std::string camera_name, camera_io::CameraModel model);
};

// Reads a camera_info YAML file. Tolerates the variants found in the wild, each with a line in
// `warnings`: no camera_name (empty), no distortion_model (plumb_bob), keys it does not know
// (ignored). A distortion_model of "none" (with no coefficients) is read as
// DistortionModel::none without a warning; an empty one is an error. Throws base::ConfigError
// ("file:line:col: field: ...") when the file cannot be read, is not YAML, misses a field the
// camera needs or holds a value out of range.
CameraInfo read_camera_info(const std::filesystem::path& path, std::vector<std::string>& warnings);
// The same for the file's text; source_name stands for the file in messages and warnings.
CameraInfo parse_camera_info(const std::string& yaml_text, const std::string& source_name,
                             std::vector<std::string>& warnings);

// The file's text, in the layout camera_calibration_parsers writes. Numbers are written in
// their shortest exact form, so that reading the text back gives the same doubles.
std::string camera_info_yaml(const CameraInfo& info);

// Writes the file all at once: a temporary file in the same folder renamed over the target, so
// that a reader never sees half a file. Throws std::runtime_error naming the file.
void write_camera_info(const std::filesystem::path& path, const CameraInfo& info);

}  // namespace flowsteer::calibration
