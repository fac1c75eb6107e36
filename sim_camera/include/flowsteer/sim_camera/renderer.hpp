#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::sim_camera {

// Where a view is taken from: an agent's head camera, aligned with its direction of motion.
struct View {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  double speed_mps = 0.0;
  double turn_rate = 0.0;  // ω about the camera's y axis, positive turns right
  CameraSpec camera;
  std::optional<std::size_t> self;  // the agent whose body is not drawn

  static View of_agent(const World& world, std::size_t agent);
  base::CameraIntrinsics intrinsics() const;
};

// What a render draws. Synthetic perception reads only the geometry channels (ids, depth,
// flow); the lit image, which needs the lights and the sun's shadow map, is for numerical flow,
// dark regions, motion energy and video.
enum class RenderChannels { all, geometry };

// One render: its channels for the same instant, row-major from the top-left pixel.
struct RenderedView {
  // CV_8UC3 BGR, lit, gamma-encoded, with the camera's noise; empty for RenderChannels::geometry
  cv::Mat image;
  cv::Mat depth_m;     // CV_32F, depth along the optical axis, +inf for the sky
  cv::Mat object_ids;  // CV_32S, agent_render_id()..., servo::kGroundId, servo::kSkyId
  cv::Mat flow;        // CV_32FC2, CGF Eq. 1 (rotation included), normalised units per second
};

// For a process that renders on several threads of its own (agents stepped in parallel): has
// Mesa's software rasteriser (llvmpipe, where there is no GPU) draw each view on the calling
// thread rather than hand it to threads of its own, which would only contend with the caller's.
// Takes effect before the process's first renderer only; an LP_NUM_THREADS the user set is kept.
void rasterize_on_calling_threads();

// How Renderer::render_geometry submits views of one size, a draw call each: into the layers of
// one framebuffer, each view's vertex shader choosing its layer (what suits a GPU: one
// framebuffer for all the views, one stall), or each into a framebuffer of its layer alone
// (what suits Mesa's software rasteriser, llvmpipe, which rasterises layered views about half
// as fast). `automatic` draws layered on a GPU whose driver lets the vertex shader choose the
// layer (GL_ARB_shader_viewport_layer_array), per view otherwise; `layered` where the driver
// lacks it is per view too.
enum class ViewSubmission { automatic, layered, per_view };

// A headless OpenGL 3.3 renderer through EGL: Mesa's surfaceless platform (llvmpipe on a
// machine without a GPU) or, where there is one, the GPU through the device platform. It draws
// lit, shadowed, procedurally textured worlds and, per pixel, the synthetic flow of CGF Eq. 1
// from the depth, the object and the known relative velocities. A renderer draws on one thread
// at a time; renderers on several threads draw at once.
// A view draws what it can show: no body outside it or between its pixel centres, and each
// cylinder with the fewest segments (48, 24, 12 or 6) whose outline stays within a quarter
// pixel of the circle's at its distance, so that a crowd's view costs what it shows rather
// than how many bodies the world holds. Faces seen from behind are culled.
class Renderer {
 public:
  // Throws std::runtime_error saying what failed when no EGL display or OpenGL 3.3 context can
  // be had.
  static std::unique_ptr<Renderer> create(ViewSubmission submission = ViewSubmission::automatic);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders the world as it is now from `view`. Reuses out's buffers when the size is the same.
  // The geometry channels are the same to the last bit whichever `channels` draws them. The
  // image has the view's camera noise (CameraSpec::noise_sigma_levels), seeded by the view's
  // agent and the world's step: the same view of the same world gives the same pixels.
  void render(const World& world, const View& view, RenderedView& out,
              RenderChannels channels = RenderChannels::all);

  // Renders the geometry channels of several views of the world as it is now: *out[k] is what
  // render(world, views[k], *out[k], RenderChannels::geometry) gives, to the last bit. The views
  // of one size are drawn as ViewSubmission says, up to 16 at a time, with one upload of the
  // world and the cameras and one make-current for all: a crowd's step is a few submissions
  // rather than one per agent. Throws std::invalid_argument when the spans' sizes differ.
  void render_geometry(const World& world, std::span<const View> views,
                       std::span<RenderedView* const> out);

  // What EGL and OpenGL report, e.g. "OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe".
  const std::string& description() const;

 private:
  struct Impl;
  explicit Renderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace flowsteer::sim_camera
