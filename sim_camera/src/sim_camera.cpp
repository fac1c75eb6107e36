#include "flowsteer/sim_camera/sim_camera.hpp"

namespace flowsteer::sim_camera {

SimCamera::SimCamera(const World& world, Renderer& renderer, std::size_t agent)
    : world_(world),
      renderer_(renderer),
      agent_(agent),
      intrinsics_(View::of_agent(world, agent).intrinsics()) {}

camera_io::ReadStatus SimCamera::read(camera_io::Frame& frame, double) {
  renderer_.render(world_, View::of_agent(world_, agent_), view_);
  frame.image = view_.image;
  frame.timestamp_s = world_.time_s();
  frame.sequence = sequence_++;
  frame.sim = camera_io::SimChannels{view_.depth_m, view_.object_ids, view_.flow};
  return camera_io::ReadStatus::ok;
}

}  // namespace flowsteer::sim_camera
