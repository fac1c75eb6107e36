#include "flowsteer/calibration/camera_info.hpp"

#include <sstream>

#include <yaml-cpp/yaml.h>

#include "flowsteer/base/atomic_file.hpp"
#include "flowsteer/base/quantity_bounds.hpp"
#include "flowsteer/base/yaml_reader.hpp"
#include "number_text.hpp"

namespace flowsteer::calibration {

namespace {

using camera_io::DistortionModel;

// The keys camera_calibration_parsers writes, in its order.
constexpr const char* kKeys[] = {"image_width",          "image_height",
                                 "camera_name",          "camera_matrix",
                                 "distortion_model",     "distortion_coefficients",
                                 "rectification_matrix", "projection_matrix"};

YAML::Node required(const base::YamlReader& reader, const YAML::Node& root, const char* key) {
  const YAML::Node node = root[key];
  if (!node) {
    reader.fail(root, key, "missing (a camera_info file needs it)");
  }
  return node;
}

// A matrix as camera_calibration_parsers writes it: {rows: R, cols: C, data: [R*C numbers]}.
// cols < 0 takes any number of columns (the distortion coefficients).
std::vector<double> matrix(const base::YamlReader& reader, const YAML::Node& root, const char* key,
                           int rows, int cols) {
  const YAML::Node node = required(reader, root, key);
  if (!node.IsMap()) {
    reader.fail(node, key, "expected a mapping with rows, cols and data");
  }
  const int got_rows =
      reader.integer(required(reader, node, "rows"), base::YamlReader::join(key, "rows"), 0);
  const int got_cols =
      reader.integer(required(reader, node, "cols"), base::YamlReader::join(key, "cols"), 0);
  if (got_rows != rows) {
    reader.fail(node["rows"], base::YamlReader::join(key, "rows"),
                "expected " + std::to_string(rows) + ", got " + std::to_string(got_rows));
  }
  if (cols >= 0 && got_cols != cols) {
    reader.fail(node["cols"], base::YamlReader::join(key, "cols"),
                "expected " + std::to_string(cols) + ", got " + std::to_string(got_cols));
  }
  const YAML::Node data = node["data"];
  const std::string field = base::YamlReader::join(key, "data");
  if (!data) {
    reader.fail(node, field, "missing");
  }
  const auto count = static_cast<std::size_t>(got_rows) * static_cast<std::size_t>(got_cols);
  if (!data.IsSequence() || data.size() != count) {
    reader.fail(data, field,
                "expected a list of " + std::to_string(count) + " numbers (rows x cols), got " +
                    (data.IsSequence() ? std::to_string(data.size()) : std::string("no list")));
  }
  std::vector<double> values;
  for (std::size_t i = 0; i < count; ++i) {
    values.push_back(reader.number(data[i], field + "[" + std::to_string(i) + "]"));
  }
  return values;
}

void write_matrix(std::ostringstream& out, const char* key, int rows, int cols,
                  const double* data) {
  out << key << ":\n  rows: " << rows << "\n  cols: " << cols << "\n  data: [";
  for (int i = 0; i < rows * cols; ++i) {
    out << (i > 0 ? ", " : "") << number_text(data[i]);
  }
  out << "]\n";
}

}  // namespace

CameraInfo CameraInfo::monocular(std::string camera_name, camera_io::CameraModel model) {
  CameraInfo info;
  info.camera_name = std::move(camera_name);
  info.projection = {model.fx, 0.0, model.cx, 0.0, 0.0, model.fy,
                     model.cy, 0.0, 0.0,      0.0, 1.0, 0.0};
  info.model = std::move(model);
  return info;
}

CameraInfo read_camera_info(const std::filesystem::path& path, std::vector<std::string>& warnings) {
  const std::string source = path.string();
  return parse_camera_info(base::read_text_file(source, "camera_info file"), source, warnings);
}

CameraInfo parse_camera_info(const std::string& yaml_text, const std::string& source,
                             std::vector<std::string>& warnings) {
  const YAML::Node root = base::load_yaml(yaml_text, source);
  const base::YamlReader reader(source);
  if (!root.IsMap()) {
    reader.fail(root, "", "expected a camera_info mapping (image_width, camera_matrix, ...)");
  }
  for (const auto& entry : root) {
    const std::string key = reader.key_text(entry.first, "");
    bool known = false;
    for (const char* k : kKeys) {
      known = known || key == k;
    }
    if (!known) {
      warnings.push_back(source + ":" + std::to_string(entry.first.Mark().line + 1) + ": " + key +
                         ": not a camera_info field, ignored");
    }
  }

  CameraInfo info;
  camera_io::CameraModel& m = info.model;
  m.width_px = reader.within_integer(required(reader, root, "image_width"), "image_width",
                                     base::bounds::kImageSide_px);
  m.height_px = reader.within_integer(required(reader, root, "image_height"), "image_height",
                                      base::bounds::kImageSide_px);
  if (const YAML::Node name = root["camera_name"]; !name) {
    warnings.push_back(source + ": camera_name: missing, left empty");
  } else if (!name.IsScalar() && !name.IsNull()) {
    reader.fail(name, "camera_name", "expected a text");
  } else if (name.IsScalar()) {
    info.camera_name = name.Scalar();
  }

  const std::vector<double> k = matrix(reader, root, "camera_matrix", 3, 3);
  const auto matrix_entry = [&](std::size_t index, const char* what, bool positive) {
    if (positive && !(k[index] > 0.0)) {
      reader.fail(root["camera_matrix"]["data"][index],
                  "camera_matrix.data[" + std::to_string(index) + "]",
                  std::string(what) + " must be positive, got " + number_text(k[index]));
    }
    return k[index];
  };
  m.fx = matrix_entry(0, "fx", true);
  m.cx = matrix_entry(2, "cx", false);
  m.fy = matrix_entry(4, "fy", true);
  m.cy = matrix_entry(5, "cy", false);

  const YAML::Node model_node = root["distortion_model"];
  if (!model_node) {
    m.distortion = DistortionModel::plumb_bob;
    warnings.push_back(source + ": distortion_model: missing, taken as plumb_bob");
  } else {
    const std::string name = model_node.IsScalar() ? model_node.Scalar() : "";
    const auto parsed = camera_io::distortion_model_from_name(name);
    if (!parsed) {
      reader.fail(
          model_node, "distortion_model",
          "expected plumb_bob, rational_polynomial, equidistant or none; got '" + name + "'");
    }
    m.distortion = *parsed;
  }
  m.coefficients = matrix(reader, root, "distortion_coefficients", 1, -1);
  const std::size_t expected = camera_io::distortion_coefficient_count(m.distortion);
  if (m.coefficients.size() != expected) {
    reader.fail(root["distortion_coefficients"], "distortion_coefficients",
                std::string(camera_io::distortion_model_name(m.distortion)) + " takes " +
                    std::to_string(expected) + " coefficients, got " +
                    std::to_string(m.coefficients.size()));
  }

  const std::vector<double> r = matrix(reader, root, "rectification_matrix", 3, 3);
  std::copy(r.begin(), r.end(), info.rectification.begin());
  const std::vector<double> p = matrix(reader, root, "projection_matrix", 3, 4);
  std::copy(p.begin(), p.end(), info.projection.begin());
  return info;
}

std::string camera_info_yaml(const CameraInfo& info) {
  const camera_io::CameraModel& m = info.model;
  m.validate();
  YAML::Emitter name;
  name << YAML::DoubleQuoted << info.camera_name;
  // ROS has no "none" model: a camera without distortion is plumb_bob with zero coefficients.
  const bool none = m.distortion == DistortionModel::none;
  const std::vector<double> coefficients = none ? std::vector<double>(5, 0.0) : m.coefficients;
  const double k[9] = {m.fx, 0.0, m.cx, 0.0, m.fy, m.cy, 0.0, 0.0, 1.0};
  std::ostringstream out;
  out << "image_width: " << m.width_px << "\nimage_height: " << m.height_px
      << "\ncamera_name: " << name.c_str() << "\n";
  write_matrix(out, "camera_matrix", 3, 3, k);
  out << "distortion_model: "
      << camera_io::distortion_model_name(none ? DistortionModel::plumb_bob : m.distortion) << "\n";
  write_matrix(out, "distortion_coefficients", 1, static_cast<int>(coefficients.size()),
               coefficients.data());
  write_matrix(out, "rectification_matrix", 3, 3, info.rectification.data());
  write_matrix(out, "projection_matrix", 3, 4, info.projection.data());
  return out.str();
}

void write_camera_info(const std::filesystem::path& path, const CameraInfo& info) {
  base::write_file_atomically(path, camera_info_yaml(info));
}

}  // namespace flowsteer::calibration
