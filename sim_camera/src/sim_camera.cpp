#include "flowsteer/sim_camera/sim_camera.hpp"

namespace flowsteer::sim_camera {

void point_frame_at(const RenderedView& view, const World& world, camera_io::Frame& frame) {
  frame.image = view.image;
  frame.timestamp_s = world.time_s();
  frame.sim = camera_io::SimChannels{view.depth_m, view.object_ids, view.flow};
}

SimCamera::SimCamera(const World& world, Renderer& renderer, std::size_t agent)
    : world_(world),
      renderer_(renderer),
      agent_(agent),
      intrinsics_(View::of_agent(world, agent).intrinsics()) {}

camera_io::ReadStatus SimCamera::read(camera_io::Frame& frame, double) {
  renderer_.render(world_, View::of_agent(world_, agent_), view_, RenderChannels::all);
  point_frame_at(view_, world_, frame);
  frame.sequence = sequence_++;
  return camera_io::ReadStatus::ok;
}

}  // namespace flowsteer::sim_camera
