#include "flowsteer/servo/analytic_scene.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace flowsteer::servo {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Nearest positive ray parameter at which origin + t·dir enters the object, or +inf.
double intersect_box(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                     const SceneObject& box) {
  const Eigen::Vector3d lo(box.position_m.x() - 0.5 * box.length_m,
                           box.position_m.y() - 0.5 * box.width_m, 0.0);
  const Eigen::Vector3d hi(box.position_m.x() + 0.5 * box.length_m,
                           box.position_m.y() + 0.5 * box.width_m, box.height_m);
  double t_near = 0.0;
  double t_far = kInf;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(dir[axis]) < 1e-15) {
      if (origin[axis] < lo[axis] || origin[axis] > hi[axis]) {
        return kInf;
      }
      continue;
    }
    double t0 = (lo[axis] - origin[axis]) / dir[axis];
    double t1 = (hi[axis] - origin[axis]) / dir[axis];
    if (t0 > t1) {
      std::swap(t0, t1);
    }
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) {
      return kInf;
    }
  }
  return t_near > 0.0 ? t_near : kInf;
}

double intersect_cylinder(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                          const SceneObject& cylinder) {
  double best = kInf;
  const Eigen::Vector2d o = origin.head<2>() - cylinder.position_m;
  const Eigen::Vector2d d = dir.head<2>();
  const double a = d.squaredNorm();
  if (a > 1e-15) {
    const double b = 2.0 * o.dot(d);
    const double c = o.squaredNorm() - cylinder.radius_m * cylinder.radius_m;
    const double disc = b * b - 4.0 * a * c;
    if (disc >= 0.0) {
      const double t = (-b - std::sqrt(disc)) / (2.0 * a);
      const double z = origin.z() + t * dir.z();
      if (t > 0.0 && z >= 0.0 && z <= cylinder.height_m) {
        best = t;
      }
    }
  }
  if (std::abs(dir.z()) > 1e-15) {  // the top cap
    const double t = (cylinder.height_m - origin.z()) / dir.z();
    if (t > 0.0 && t < best && (o + t * d).norm() <= cylinder.radius_m) {
      best = t;
    }
  }
  return best;
}

bool contains(const SceneObject& object, const Eigen::Vector3d& p) {
  if (p.z() < 0.0 || p.z() > object.height_m) {
    return false;
  }
  const Eigen::Vector2d d = p.head<2>() - object.position_m;
  if (object.shape == SceneObject::Shape::cylinder) {
    return d.norm() <= object.radius_m;
  }
  return std::abs(d.x()) <= 0.5 * object.length_m && std::abs(d.y()) <= 0.5 * object.width_m;
}

Eigen::Vector3d relative_velocity_camera(const AnalyticScene& scene,
                                         const Eigen::Vector2d& velocity_mps) {
  const Eigen::Vector3d relative_body(velocity_mps.x() - scene.agent_speed_mps, velocity_mps.y(),
                                      0.0);
  return scene.mount.camera_to_body().transpose() * relative_body;
}

}  // namespace

void AnalyticScene::validate() const {
  intrinsics.validate();
  mount.validate();
  if (!std::isfinite(agent_speed_mps) || !std::isfinite(agent_turn_rate)) {
    throw std::invalid_argument("scene: agent speed and turn rate must be finite");
  }
  const Eigen::Vector3d camera(0.0, 0.0, mount.height_m);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const SceneObject& o = objects[i];
    const std::string name =
        "scene: object " + std::to_string(i) + " (id " + std::to_string(o.id) + ")";
    if (o.id < 0) {
      throw std::invalid_argument(name + ": id must be >= 0");
    }
    const bool box = o.shape == SceneObject::Shape::box;
    if (!o.position_m.allFinite() || !o.velocity_mps.allFinite()) {
      throw std::invalid_argument(name + ": position and velocity must be finite");
    }
    if (!(o.height_m > 0.0) || (box && !(o.length_m > 0.0 && o.width_m > 0.0)) ||
        (!box && !(o.radius_m > 0.0))) {
      throw std::invalid_argument(name + ": sizes must be positive");
    }
    if (contains(o, camera)) {
      throw std::invalid_argument(name + ": the camera is inside it");
    }
  }
}

SceneRender render_scene(const AnalyticScene& scene) {
  scene.validate();
  SceneRender out{FlowField(scene.intrinsics, true), {}};
  FlowField& field = out.flow;
  out.ids.assign(field.size(), kSkyId);
  const Eigen::Matrix3d r = scene.mount.camera_to_body();
  const Eigen::Vector3d origin(0.0, 0.0, scene.mount.height_m);
  const Eigen::Vector3d omega =
      camera_angular_velocity(scene.agent_turn_rate, scene.mount.pitch_rad);
  const Eigen::Vector3d ground_velocity = relative_velocity_camera(scene, Eigen::Vector2d::Zero());
  std::vector<Eigen::Vector3d> object_velocities;
  object_velocities.reserve(scene.objects.size());
  for (const SceneObject& o : scene.objects) {
    object_velocities.push_back(relative_velocity_camera(scene, o.velocity_mps));
  }

  auto depth = field.depth();
  auto flow = field.flow();
  for (int row = 0; row < field.height(); ++row) {
    const double y = field.y(row);
    for (int col = 0; col < field.width(); ++col) {
      const double x = field.x(col);
      // The ray through (x, y, 1) in the camera frame: its parameter is the depth Z.
      const Eigen::Vector3d dir = r * Eigen::Vector3d(x, y, 1.0);
      double best = kInf;
      std::int32_t id = kSkyId;
      const Eigen::Vector3d* velocity = nullptr;
      if (scene.ground && dir.z() < -1e-12) {
        best = -origin.z() / dir.z();
        id = kGroundId;
        velocity = &ground_velocity;
      }
      for (std::size_t k = 0; k < scene.objects.size(); ++k) {
        const SceneObject& o = scene.objects[k];
        const double t = o.shape == SceneObject::Shape::box ? intersect_box(origin, dir, o)
                                                            : intersect_cylinder(origin, dir, o);
        if (t < best) {
          best = t;
          id = o.id;
          velocity = &object_velocities[k];
        }
      }
      const std::size_t i = field.index(col, row);
      out.ids[i] = id;
      Eigen::Vector2d u = rotational_flow(x, y, omega);
      if (velocity != nullptr) {
        const Eigen::Vector3d& v = *velocity;
        u += Eigen::Vector2d(v.x() - x * v.z(), v.y() - y * v.z()) / best;  // CGF Eq. 1
        depth[i] = static_cast<float>(best);
      }
      flow[i] = u.cast<float>();
    }
  }
  return out;
}

ObjectTruth object_truth(const AnalyticScene& scene, const SceneObject& object) {
  ObjectTruth truth;
  truth.relative_velocity_mps = relative_velocity_camera(scene, object.velocity_mps);
  const Eigen::Vector3d& v = truth.relative_velocity_mps;
  truth.foe = Eigen::Vector2d(v.x() / v.z(), v.y() / v.z());  // CGF Eq. 3
  const Eigen::Vector3d centre(object.position_m.x(), object.position_m.y(), scene.mount.height_m);
  const Eigen::Vector3d in_camera = scene.mount.camera_to_body().transpose() *
                                    (centre - Eigen::Vector3d(0.0, 0.0, scene.mount.height_m));
  truth.centre_depth_m = in_camera.z();
  truth.ttc_s = -truth.centre_depth_m / v.z();
  return truth;
}

}  // namespace flowsteer::servo
