#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "flowsteer/recording/ros2_messages.hpp"

namespace flowsteer::recording::foxglove {

// Foxglove's message schemas (https://docs.foxglove.dev/docs/visualization/message-schemas) that a
// recording uses, encoded as JSON: the world as 3D primitives (SceneUpdate) and what perception
// found drawn on the camera image (ImageAnnotations). Each has its schema name and a JSON Schema
// of what is written, for the MCAP Schema record.

struct Color {
  double r = 0.0, g = 0.0, b = 0.0, a = 1.0;  // each in [0, 1]
};

// A box or an upright cylinder: pose of its centre, size along its axes (a cylinder's x and y are
// its diameter).
struct Solid {
  ros2::Pose pose;
  ros2::Vector3 size;
  Color color;
};

struct Label {
  ros2::Pose pose;
  std::string text;
  double font_size = 12.0;  // px: drawn at a constant size on screen
  Color color;
};

struct SceneEntity {
  std::string id;  // an entity replaces the one with its id
  std::string frame_id;
  std::vector<Solid> cubes;
  std::vector<Solid> cylinders;
  std::vector<Label> texts;
};

std::string scene_update_json(std::uint64_t t_ns, std::span<const SceneEntity> entities);
inline constexpr const char* kSceneUpdate = "foxglove.SceneUpdate";
const std::string& scene_update_schema();

struct ImagePoint {
  double x = 0.0, y = 0.0;  // px, from the image's top-left corner
};

struct ImageCircle {
  ImagePoint centre;
  double diameter_px = 0.0;
  double thickness_px = 1.0;
  Color outline;
};

struct ImagePolyline {
  std::vector<ImagePoint> points;
  bool closed = false;  // a loop, else a strip
  double thickness_px = 1.0;
  Color outline;
};

struct ImageText {
  ImagePoint position;  // the text's bottom-left corner
  std::string text;
  double font_size_px = 12.0;
  Color color;
};

struct ImageAnnotations {
  std::vector<ImageCircle> circles;
  std::vector<ImagePolyline> polylines;
  std::vector<ImageText> texts;
};

std::string image_annotations_json(std::uint64_t t_ns, const ImageAnnotations& annotations);
inline constexpr const char* kImageAnnotations = "foxglove.ImageAnnotations";
const std::string& image_annotations_schema();

// {"sec": …, "nsec": …}, Foxglove's time.
std::string json_time(std::uint64_t t_ns);

}  // namespace flowsteer::recording::foxglove
