#include "flowsteer/recording/foxglove_messages.hpp"

#include <cmath>

#include "flowsteer/base/output_files.hpp"

namespace flowsteer::recording::foxglove {

namespace {

std::string num(double v) {
  return base::json_number(v, base::Digits::exact);
}

std::string color(const Color& c) {
  return "{\"r\":" + num(c.r) + ",\"g\":" + num(c.g) + ",\"b\":" + num(c.b) + ",\"a\":" + num(c.a) +
         "}";
}

std::string vector3(const ros2::Vector3& v) {
  return "{\"x\":" + num(v.x) + ",\"y\":" + num(v.y) + ",\"z\":" + num(v.z) + "}";
}

std::string pose(const ros2::Pose& p) {
  const ros2::Quaternion& q = p.orientation;
  return "{\"position\":" + vector3(p.position) + ",\"orientation\":{\"x\":" + num(q.x) +
         ",\"y\":" + num(q.y) + ",\"z\":" + num(q.z) + ",\"w\":" + num(q.w) + "}}";
}

std::string point(const ImagePoint& p) {
  return "{\"x\":" + num(p.x) + ",\"y\":" + num(p.y) + "}";
}

template <typename Item, typename Write>
std::string array(const std::vector<Item>& items, Write write) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) {
      out += ',';
    }
    out += write(items[i]);
  }
  out += ']';
  return out;
}

std::string entity(const SceneEntity& e, const std::string& time) {
  const auto cube = [](const Solid& s) {
    return "{\"pose\":" + pose(s.pose) + ",\"size\":" + vector3(s.size) +
           ",\"color\":" + color(s.color) + "}";
  };
  const auto cylinder = [](const Solid& s) {
    return "{\"pose\":" + pose(s.pose) + ",\"size\":" + vector3(s.size) +
           ",\"bottom_scale\":1,\"top_scale\":1,\"color\":" + color(s.color) + "}";
  };
  const auto text = [](const Label& l) {
    return "{\"pose\":" + pose(l.pose) + ",\"billboard\":true,\"font_size\":" + num(l.font_size) +
           ",\"scale_invariant\":true,\"color\":" + color(l.color) +
           ",\"text\":" + base::json_string(l.text) + "}";
  };
  return "{\"timestamp\":" + time + ",\"frame_id\":" + base::json_string(e.frame_id) +
         ",\"id\":" + base::json_string(e.id) +
         ",\"lifetime\":{\"sec\":0,\"nsec\":0},\"frame_locked\":false,\"metadata\":[],"
         "\"arrows\":[],\"cubes\":" +
         array(e.cubes, cube) + ",\"spheres\":[],\"cylinders\":" + array(e.cylinders, cylinder) +
         ",\"lines\":[],\"triangles\":[],\"texts\":" + array(e.texts, text) + ",\"models\":[]}";
}

// The JSON Schema of a {sec, nsec} time, a colour, a pose and a vector, for the schemas below.
constexpr const char* kDefinitions = R"("$defs":{
 "time":{"type":"object","properties":{"sec":{"type":"integer","minimum":0},
  "nsec":{"type":"integer","minimum":0,"maximum":999999999}},"required":["sec","nsec"]},
 "color":{"type":"object","properties":{"r":{"type":"number"},"g":{"type":"number"},
  "b":{"type":"number"},"a":{"type":"number"}},"required":["r","g","b","a"]},
 "vector3":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},
  "z":{"type":"number"}},"required":["x","y","z"]},
 "point2":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"}},
  "required":["x","y"]},
 "pose":{"type":"object","properties":{"position":{"$ref":"#/$defs/vector3"},
  "orientation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},
  "z":{"type":"number"},"w":{"type":"number"}},"required":["x","y","z","w"]}},
  "required":["position","orientation"]}})";

}  // namespace

std::string json_time(std::uint64_t t_ns) {
  return "{\"sec\":" + std::to_string(t_ns / 1'000'000'000) +
         ",\"nsec\":" + std::to_string(t_ns % 1'000'000'000) + "}";
}

std::string scene_update_json(std::uint64_t t_ns, std::span<const SceneEntity> entities) {
  const std::string time = json_time(t_ns);
  std::string out = "{\"deletions\":[],\"entities\":[";
  for (std::size_t i = 0; i < entities.size(); ++i) {
    if (i > 0) {
      out += ',';
    }
    out += entity(entities[i], time);
  }
  out += "]}";
  return out;
}

const std::string& scene_update_schema() {
  static const std::string schema = std::string(R"({"title":"foxglove.SceneUpdate",
"description":"3D primitives in a frame: flowsteer writes cubes, cylinders and texts",
"type":"object",)") + kDefinitions + R"(,
"properties":{"deletions":{"type":"array"},"entities":{"type":"array","items":{"type":"object",
 "properties":{"timestamp":{"$ref":"#/$defs/time"},"frame_id":{"type":"string"},
  "id":{"type":"string"},"lifetime":{"$ref":"#/$defs/time"},"frame_locked":{"type":"boolean"},
  "cubes":{"type":"array","items":{"type":"object","properties":{"pose":{"$ref":"#/$defs/pose"},
   "size":{"$ref":"#/$defs/vector3"},"color":{"$ref":"#/$defs/color"}}}},
  "cylinders":{"type":"array","items":{"type":"object","properties":{
   "pose":{"$ref":"#/$defs/pose"},"size":{"$ref":"#/$defs/vector3"},
   "bottom_scale":{"type":"number"},"top_scale":{"type":"number"},
   "color":{"$ref":"#/$defs/color"}}}},
  "texts":{"type":"array","items":{"type":"object","properties":{"pose":{"$ref":"#/$defs/pose"},
   "billboard":{"type":"boolean"},"font_size":{"type":"number"},
   "scale_invariant":{"type":"boolean"},"color":{"$ref":"#/$defs/color"},
   "text":{"type":"string"}}}}},
 "required":["timestamp","frame_id","id","cubes","cylinders","texts"]}}},
"required":["deletions","entities"]})";
  return schema;
}

std::string image_annotations_json(std::uint64_t t_ns, const ImageAnnotations& a) {
  const std::string time = json_time(t_ns);
  const std::string clear = color({0.0, 0.0, 0.0, 0.0});
  const auto circle = [&](const ImageCircle& c) {
    return "{\"timestamp\":" + time + ",\"position\":" + point(c.centre) +
           ",\"diameter\":" + num(c.diameter_px) + ",\"thickness\":" + num(c.thickness_px) +
           ",\"fill_color\":" + clear + ",\"outline_color\":" + color(c.outline) + "}";
  };
  const auto polyline = [&](const ImagePolyline& p) {
    // Foxglove's PointsAnnotation type: 2 a closed loop, 3 a strip.
    return "{\"timestamp\":" + time + ",\"type\":" + (p.closed ? "2" : "3") +
           ",\"points\":" + array(p.points, point) + ",\"outline_color\":" + color(p.outline) +
           ",\"outline_colors\":[],\"fill_color\":" + clear +
           ",\"thickness\":" + num(p.thickness_px) + "}";
  };
  const auto text = [&](const ImageText& t) {
    return "{\"timestamp\":" + time + ",\"position\":" + point(t.position) +
           ",\"text\":" + base::json_string(t.text) + ",\"font_size\":" + num(t.font_size_px) +
           ",\"text_color\":" + color(t.color) +
           ",\"background_color\":" + color({0.0, 0.0, 0.0, 0.5}) + "}";
  };
  return "{\"circles\":" + array(a.circles, circle) +
         ",\"points\":" + array(a.polylines, polyline) + ",\"texts\":" + array(a.texts, text) + "}";
}

const std::string& image_annotations_schema() {
  static const std::string schema = std::string(R"({"title":"foxglove.ImageAnnotations",
"description":"Circles, polylines and texts on a camera image, in pixels",
"type":"object",)") + kDefinitions + R"(,
"properties":{
 "circles":{"type":"array","items":{"type":"object","properties":{
  "timestamp":{"$ref":"#/$defs/time"},"position":{"$ref":"#/$defs/point2"},
  "diameter":{"type":"number"},"thickness":{"type":"number"},
  "fill_color":{"$ref":"#/$defs/color"},"outline_color":{"$ref":"#/$defs/color"}},
  "required":["timestamp","position","diameter","thickness","fill_color","outline_color"]}},
 "points":{"type":"array","items":{"type":"object","properties":{
  "timestamp":{"$ref":"#/$defs/time"},"type":{"type":"integer","minimum":0,"maximum":4},
  "points":{"type":"array","items":{"$ref":"#/$defs/point2"}},
  "outline_color":{"$ref":"#/$defs/color"},"outline_colors":{"type":"array"},
  "fill_color":{"$ref":"#/$defs/color"},"thickness":{"type":"number"}},
  "required":["timestamp","type","points","outline_color","thickness"]}},
 "texts":{"type":"array","items":{"type":"object","properties":{
  "timestamp":{"$ref":"#/$defs/time"},"position":{"$ref":"#/$defs/point2"},
  "text":{"type":"string"},"font_size":{"type":"number"},
  "text_color":{"$ref":"#/$defs/color"},"background_color":{"$ref":"#/$defs/color"}},
  "required":["timestamp","position","text","font_size","text_color"]}}},
"required":["circles","points","texts"]})";
  return schema;
}

}  // namespace flowsteer::recording::foxglove
