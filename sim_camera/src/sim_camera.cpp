#include "flowsteer/sim_camera/sim_camera.hpp"

namespace flowsteer::sim_camera {

void render_frame(Renderer& renderer, const World& world, std::size_t agent,
                  RenderChannels channels, RenderedView& view, camera_io::Frame& frame) {
  renderer.render(world, View::of_agent(world, agent), view, channels);
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
  render_frame(renderer_, world_, agent_, RenderChannels::all, view_, frame);
  frame.sequence = sequence_++;
  return camera_io::ReadStatus::ok;
}

}  // namespace flowsteer::sim_camera
