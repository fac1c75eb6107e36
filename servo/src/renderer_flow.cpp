#include "renderer_flow.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace flowsteer::servo {

FlowStatus RendererFlow::update(const FlowFrame& frame, const CameraMotion& motion,
                                FlowField& field) {
  if (frame.renderer_flow == nullptr || frame.renderer_depth_m == nullptr) {
    throw std::invalid_argument("the renderer's flow needs a simulator's frames");
  }
  const cv::Mat& renderer_flow = *frame.renderer_flow;
  if (renderer_flow.empty())
    return FlowStatus::empty_frame;
  if (renderer_flow.cols != field.width() || renderer_flow.rows != field.height())
    return FlowStatus::size_changed;

  auto flow = field.flow();
  auto depth = field.depth();
  const Eigen::Vector2f no_flow =
      Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  for (int row = 0; row < field.height(); ++row) {
    const auto* f = renderer_flow.ptr<cv::Vec2f>(row);
    const auto* d = frame.renderer_depth_m->ptr<float>(row);
    for (int col = 0; col < field.width(); ++col) {
      const std::size_t i = field.index(col, row);
      flow[i] = options_.no_flow_without_depth && !std::isfinite(d[col])
                    ? no_flow
                    : Eigen::Vector2f(f[col][0], f[col][1]);
      if (!depth.empty())
        depth[i] = d[col];
    }
  }
  derotate(field, motion.angular_velocity);
  return FlowStatus::ok;
}

}  // namespace flowsteer::servo
