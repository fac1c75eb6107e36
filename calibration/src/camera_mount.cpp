#include "flowsteer/calibration/camera_mount.hpp"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "flowsteer/base/atomic_file.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "number_text.hpp"

namespace flowsteer::calibration {

namespace {

double degrees(double rad) {
  return rad * 180.0 / std::numbers::pi;
}

}  // namespace

MountCalibration read_camera_mount(const std::filesystem::path& path) {
  const std::string source = path.string();
  return parse_camera_mount(base::read_text_file(source, "camera mount file"), source);
}

MountCalibration parse_camera_mount(const std::string& yaml_text, const std::string& source) {
  const YAML::Node root = base::load_yaml(yaml_text, source);
  const base::YamlReader reader(source);
  if (!root.IsMap()) {
    reader.fail(root, "", "expected a camera mount mapping (height_m, pitch_rad, roll_rad)");
  }
  reader.only_keys(root, "", {"height_m", "pitch_rad", "roll_rad"});
  for (const char* key : {"height_m", "pitch_rad"}) {
    if (!root[key]) {
      reader.fail(root, key, "missing (a camera mount file needs height_m and pitch_rad)");
    }
  }
  MountCalibration m;
  m.mount.height_m = reader.within(root["height_m"], "height_m", base::bounds::kCameraHeight_m);
  m.mount.pitch_rad = reader.within(root["pitch_rad"], "pitch_rad", base::bounds::kCameraPitch_rad);
  m.roll_rad = root["roll_rad"]
                   ? reader.within(root["roll_rad"], "roll_rad", base::bounds::kCameraPitch_rad)
                   : 0.0;
  return m;
}

std::string camera_mount_yaml(const MountCalibration& m) {
  m.mount.validate();
  if (!std::isfinite(m.roll_rad)) {
    throw std::invalid_argument("camera mount: roll_rad is not finite");
  }
  std::ostringstream out;
  out << "# Camera mount above a flat floor (flowsteer calibrate mount).\n"
      << "# height_m: optical centre above the floor; pitch_rad: optical axis below the horizon,\n"
      << "# positive looks down; roll_rad: about the optical axis, positive turns the image's\n"
      << "# right side down.\n"
      << "height_m: " << number_text(m.mount.height_m) << "\n"
      << "pitch_rad: " << number_text(m.mount.pitch_rad) << "  # "
      << number_text(std::round(degrees(m.mount.pitch_rad) * 100.0) / 100.0) << " deg\n"
      << "roll_rad: " << number_text(m.roll_rad) << "  # "
      << number_text(std::round(degrees(m.roll_rad) * 100.0) / 100.0) << " deg\n";
  return out.str();
}

void write_camera_mount(const std::filesystem::path& path, const MountCalibration& mount) {
  base::write_file_atomically(path, camera_mount_yaml(mount));
}

}  // namespace flowsteer::calibration
