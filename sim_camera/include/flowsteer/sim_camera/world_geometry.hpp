#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/servo/geometric_features.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::sim_camera {

// Every body of the world but the agent itself (other agents, obstacles, moving obstacles), as
// exact geometry in that agent's body frame, for the geometric reference controller. Ids are
// the renderer's (agent_render_id, ...), so that a body keeps the id its image region would
// have. Cylinders and agents become regular polygons circumscribing their circle. Keeps its
// storage between calls.
class WorldGeometry {
 public:
  std::span<const servo::GeometricBody> bodies_seen_by(const World& world, std::size_t agent);

 private:
  std::vector<Eigen::Vector2d> points_;
  std::vector<std::size_t> offsets_;
  std::vector<servo::GeometricBody> bodies_;
};

}  // namespace flowsteer::sim_camera
