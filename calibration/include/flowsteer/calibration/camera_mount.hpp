#pragma once

#include <filesystem>
#include <string>

#include "flowsteer/base/camera.hpp"

namespace flowsteer::calibration {

// The camera's pose above a flat floor, as `flowsteer calibrate mount` measures it and the launch
// files point to. base::CameraMount holds what the servo core uses (height, pitch); roll is
// kept beside it: the core assumes a level camera, so a user can see how far from level it is.
struct MountCalibration {
  base::CameraMount mount;
  // Rotation about the optical axis; positive turns the camera's x axis (image right) down
  // towards the floor.
  double roll_rad = 0.0;
};

// Reads a camera mount file:
//   height_m: 0.42    # optical centre above the floor, > 0
//   pitch_rad: 0.35   # optical axis below the horizon (positive looks down), |pitch| < 90°
//   roll_rad: 0.01    # optional, 0 when absent
// Throws base::ConfigError ("file:line:col: field: ...") for a missing, unknown or out-of-range
// field.
MountCalibration read_camera_mount(const std::filesystem::path& path);
// The same for the file's text; source_name stands for the file in messages.
MountCalibration parse_camera_mount(const std::string& yaml_text, const std::string& source_name);

// The file's text, with comments that say what each field means; exact round trip.
std::string camera_mount_yaml(const MountCalibration& mount);

// Writes the file all at once (a temporary file renamed over the target). Throws
// std::runtime_error naming the file.
void write_camera_mount(const std::filesystem::path& path, const MountCalibration& mount);

}  // namespace flowsteer::calibration
