#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

// A scene described in the agent's body frame (x forward, y left, z up; the ground is z = 0)
// whose flow is computed exactly per pixel by ray casting: a reference for tests and the
// `flowsteer demo` command, independent of any renderer.
struct SceneObject {
  enum class Shape { box, cylinder };
  Shape shape = Shape::box;
  std::int32_t id = 0;                                   // >= 0; written to the id image
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  // centre of the footprint
  double length_m = 1.0;                                 // box: extent along x
  double width_m = 1.0;                                  // box: extent along y
  double radius_m = 0.5;                                 // cylinder
  double height_m = 1.8;
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();  // over the ground, body axes
};

struct AnalyticScene {
  base::CameraIntrinsics intrinsics;
  base::CameraMount mount;
  double agent_speed_mps = 1.0;
  double agent_turn_rate = 0.0;  // ω about the camera's y axis, positive turns right
  bool ground = true;
  std::vector<SceneObject> objects;

  // Throws std::invalid_argument naming the offending object or field.
  void validate() const;
};

struct SceneRender {
  FlowField flow;  // raw flow (CGF Eq. 1, rotation included) with depth
  std::vector<std::int32_t> ids;
};

SceneRender render_scene(const AnalyticScene& scene);

// Ground truth of an object's motion relative to the camera.
struct ObjectTruth {
  Eigen::Vector3d relative_velocity_mps;  // camera frame
  Eigen::Vector2d foe;                    // CGF Eq. 3
  double centre_depth_m = 0.0;            // depth of the footprint centre at camera height
  double ttc_s = 0.0;                     // −Z / v_z at that depth
};

ObjectTruth object_truth(const AnalyticScene& scene, const SceneObject& object);

}  // namespace flowsteer::servo
