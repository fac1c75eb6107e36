#include "flowsteer/recording/ros2_messages.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "flowsteer/recording/cdr.hpp"
#include "flowsteer/recording/recording_error.hpp"
#include "msg_definitions.hpp"

namespace flowsteer::recording::ros2 {

namespace {

// A type's .msg text (msg/, compiled in) and the types its fields name, as "package/Type".
struct Definition {
  std::string text;
  std::vector<std::string> uses;
};

// The types a .msg text's fields name: a field is "<type>[array] <name> [default]"; a type with
// a '/' names its package, one that starts with a capital letter is of `package`.
std::vector<std::string> used_types(const std::string& text, const std::string& package) {
  std::vector<std::string> uses;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::string type = line.substr(0, line.find_first_of(" \t["));
    if (type.empty() || !(type.find('/') != std::string::npos || std::isupper(type[0]))) {
      continue;
    }
    if (type.find('/') == std::string::npos) {
      type = package + "/" + type;
    }
    if (std::find(uses.begin(), uses.end(), type) == uses.end()) {
      uses.push_back(type);
    }
  }
  return uses;
}

const std::map<std::string, Definition>& definitions() {
  static const std::map<std::string, Definition> table = [] {
    std::map<std::string, Definition> t;
    for (const auto& [name, text] : kMsgDefinitions) {
      const std::string type = name;
      t[type] = {text, used_types(text, type.substr(0, type.find('/')))};
    }
    return t;
  }();
  return table;
}

void add_dependencies(const std::string& type, std::vector<std::string>& seen) {
  for (const std::string& used : definitions().at(type).uses) {
    if (std::find(seen.begin(), seen.end(), used) == seen.end()) {
      seen.emplace_back(used);
      add_dependencies(used, seen);
    }
  }
}

// The type's text, then each type it uses, directly or not, once, in the order first met.
std::string schema_text(const std::string& type) {
  std::string text = definitions().at(type).text;
  std::vector<std::string> dependencies;
  add_dependencies(type, dependencies);
  for (const std::string& d : dependencies) {
    text += std::string(80, '=') + "\nMSG: " + d + "\n" + definitions().at(d).text;
  }
  return text;
}

void write_header(CdrWriter& w, const Header& h) {
  w.i32(h.stamp.sec);
  w.u32(h.stamp.nanosec);
  w.string(h.frame_id);
}

Header read_header(CdrReader& r) {
  Header h;
  h.stamp.sec = r.i32("header.stamp.sec");
  h.stamp.nanosec = r.u32("header.stamp.nanosec");
  // A stamp is a time since an epoch: never before it, its nanoseconds less than a second.
  if (h.stamp.sec < 0 || h.stamp.nanosec >= 1'000'000'000) {
    throw RecordingError("CDR field header.stamp: " + std::to_string(h.stamp.sec) + " s " +
                         std::to_string(h.stamp.nanosec) + " ns is not a time");
  }
  h.frame_id = r.string("header.frame_id");
  return h;
}

void write_vector(CdrWriter& w, const Vector3& v) {
  w.f64(v.x);
  w.f64(v.y);
  w.f64(v.z);
}

Vector3 read_vector(CdrReader& r, const char* field) {
  return {r.f64(field), r.f64(field), r.f64(field)};
}

void write_quaternion(CdrWriter& w, const Quaternion& q) {
  w.f64(q.x);
  w.f64(q.y);
  w.f64(q.z);
  w.f64(q.w);
}

Quaternion read_quaternion(CdrReader& r, const char* field) {
  return {r.f64(field), r.f64(field), r.f64(field), r.f64(field)};
}

void write_twist(CdrWriter& w, const Twist& t) {
  write_vector(w, t.linear);
  write_vector(w, t.angular);
}

Twist read_twist(CdrReader& r) {
  Twist t;
  t.linear = read_vector(r, "linear");
  t.angular = read_vector(r, "angular");
  return t;
}

}  // namespace

const std::string& ros2msg_schema(const std::string& package_type) {
  static const std::map<std::string, std::string> schemas = [] {
    std::map<std::string, std::string> all;
    for (const auto& [type, definition] : definitions()) {
      all[type] = schema_text(type);
    }
    return all;
  }();
  return schemas.at(package_type);
}

Time Time::from_ns(std::uint64_t t_ns) {
  const std::uint64_t sec = t_ns / 1'000'000'000;
  if (sec > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
    throw std::invalid_argument("ros2::Time: " + std::to_string(t_ns) +
                                " ns is past what ROS 2's int32 seconds hold");
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(t_ns % 1'000'000'000)};
}

std::uint64_t Time::ns() const {
  return static_cast<std::uint64_t>(sec) * 1'000'000'000 + nanosec;
}

Quaternion Quaternion::from_yaw(double yaw_rad) {
  return {0.0, 0.0, std::sin(0.5 * yaw_rad), std::cos(0.5 * yaw_rad)};
}

double Quaternion::yaw_rad() const {
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

void MessageType<Twist>::encode(const Twist& m, std::vector<std::uint8_t>& out) {
  CdrWriter w(out);
  write_twist(w, m);
}
Twist MessageType<Twist>::decode(std::span<const std::uint8_t> data) {
  CdrReader r(data);
  return read_twist(r);
}

void MessageType<Odometry>::encode(const Odometry& m, std::vector<std::uint8_t>& out) {
  CdrWriter w(out);
  write_header(w, m.header);
  w.string(m.child_frame_id);
  write_vector(w, m.pose.position);
  write_quaternion(w, m.pose.orientation);
  w.f64_array(m.pose_covariance);
  write_twist(w, m.twist);
  w.f64_array(m.twist_covariance);
}
Odometry MessageType<Odometry>::decode(std::span<const std::uint8_t> data) {
  CdrReader r(data);
  Odometry m;
  m.header = read_header(r);
  m.child_frame_id = r.string("child_frame_id");
  m.pose.position = read_vector(r, "pose.pose.position");
  m.pose.orientation = read_quaternion(r, "pose.pose.orientation");
  r.f64_array(m.pose_covariance, "pose.covariance");
  m.twist = read_twist(r);
  r.f64_array(m.twist_covariance, "twist.covariance");
  return m;
}

void MessageType<TFMessage>::encode(const TFMessage& m, std::vector<std::uint8_t>& out) {
  CdrWriter w(out);
  w.u32(static_cast<std::uint32_t>(m.transforms.size()));
  for (const TransformStamped& t : m.transforms) {
    write_header(w, t.header);
    w.string(t.child_frame_id);
    write_vector(w, t.translation);
    write_quaternion(w, t.rotation);
  }
}
TFMessage MessageType<TFMessage>::decode(std::span<const std::uint8_t> data) {
  CdrReader r(data);
  TFMessage m;
  // A transform holds at least its stamp, two string lengths and seven float64.
  m.transforms.resize(r.count("transforms", 4 + 4 + 4 + 4 + 7 * 8));
  for (TransformStamped& t : m.transforms) {
    t.header = read_header(r);
    t.child_frame_id = r.string("transforms.child_frame_id");
    t.translation = read_vector(r, "transforms.transform.translation");
    t.rotation = read_quaternion(r, "transforms.transform.rotation");
  }
  return m;
}

void MessageType<CompressedImage>::encode(const CompressedImage& m,
                                          std::vector<std::uint8_t>& out) {
  CdrWriter w(out);
  write_header(w, m.header);
  w.string(m.format);
  w.bytes(m.data);
}
CompressedImage MessageType<CompressedImage>::decode(std::span<const std::uint8_t> data) {
  CdrReader r(data);
  CompressedImage m;
  m.header = read_header(r);
  m.format = r.string("format");
  const std::span<const std::uint8_t> bytes = r.bytes("data");
  m.data.assign(bytes.begin(), bytes.end());
  return m;
}

void MessageType<Image>::encode(const Image& m, std::vector<std::uint8_t>& out) {
  CdrWriter w(out);
  write_header(w, m.header);
  w.u32(m.height);
  w.u32(m.width);
  w.string(m.encoding);
  w.u8(m.is_bigendian);
  w.u32(m.step);
  w.bytes(m.data);
}
Image MessageType<Image>::decode(std::span<const std::uint8_t> data) {
  CdrReader r(data);
  Image m;
  m.header = read_header(r);
  m.height = r.u32("height");
  m.width = r.u32("width");
  m.encoding = r.string("encoding");
  m.is_bigendian = r.u8("is_bigendian");
  m.step = r.u32("step");
  const std::span<const std::uint8_t> bytes = r.bytes("data");
  m.data.assign(bytes.begin(), bytes.end());
  return m;
}

void MessageType<CameraInfo>::encode(const CameraInfo& m, std::vector<std::uint8_t>& out) {
  CdrWriter w(out);
  write_header(w, m.header);
  w.u32(m.height);
  w.u32(m.width);
  w.string(m.distortion_model);
  w.f64_sequence(m.d);
  w.f64_array(m.k);
  w.f64_array(m.r);
  w.f64_array(m.p);
  w.u32(m.binning_x);
  w.u32(m.binning_y);
  w.u32(m.roi.x_offset);
  w.u32(m.roi.y_offset);
  w.u32(m.roi.height);
  w.u32(m.roi.width);
  w.u8(m.roi.do_rectify ? 1 : 0);
}
CameraInfo MessageType<CameraInfo>::decode(std::span<const std::uint8_t> data) {
  CdrReader r(data);
  CameraInfo m;
  m.header = read_header(r);
  m.height = r.u32("height");
  m.width = r.u32("width");
  m.distortion_model = r.string("distortion_model");
  m.d = r.f64_sequence("d");
  r.f64_array(m.k, "k");
  r.f64_array(m.r, "r");
  r.f64_array(m.p, "p");
  m.binning_x = r.u32("binning_x");
  m.binning_y = r.u32("binning_y");
  m.roi.x_offset = r.u32("roi.x_offset");
  m.roi.y_offset = r.u32("roi.y_offset");
  m.roi.height = r.u32("roi.height");
  m.roi.width = r.u32("roi.width");
  m.roi.do_rectify = r.u8("roi.do_rectify") != 0;
  return m;
}

}  // namespace flowsteer::recording::ros2
