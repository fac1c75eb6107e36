#include "flowsteer/pipeline/overlay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

namespace flowsteer::pipeline {

namespace {

const cv::Scalar kFoeColor(255, 120, 0);
const cv::Scalar kCentreColor(0, 140, 255);
const cv::Scalar kGoalColor(200, 80, 255);
constexpr int kMinOverlayWidthPx = 640;

// Where a normalised image point lies in the image enlarged `scale` times: its pixel's centre.
struct EnlargedView {
  const base::CameraIntrinsics& k;
  int scale;
  cv::Point px(const Eigen::Vector2d& p) const {
    return {static_cast<int>(std::lround((k.fx_px * p.x() + k.cx_px + 0.5) * scale - 0.5)),
            static_cast<int>(std::lround((k.fy_px * p.y() + k.cy_px + 0.5) * scale - 0.5))};
  }
};

// An object's centre and, where it has one, its FOE and its TTC; sized for the enlarged view.
void draw_object(cv::Mat& view, const servo::ObjectFeatures& o, const EnlargedView& enlarged) {
  const double font = std::max(0.7, view.cols / 550.0);
  const int mark_px = std::max(3, view.cols / 100);
  const cv::Point centre = enlarged.px(o.centre);
  if (o.has_foe()) {
    const cv::Point foe = enlarged.px(o.foe);
    cv::circle(view, foe, mark_px + 1, kFoeColor, 2, cv::LINE_AA);
    cv::line(view, foe, centre, kFoeColor, 2, cv::LINE_AA);
  }
  cv::circle(view, centre, mark_px, kCentreColor, cv::FILLED, cv::LINE_AA);  // over the FOE's line
  if (!o.has_foe()) {
    return;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.1fs", o.ttc_s);
  // Outlined in black: legible on the sky, the ground and the objects alike.
  const cv::Point at = centre + cv::Point(mark_px + 2, -mark_px - 2);
  cv::putText(view, text, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar::all(0), 4, cv::LINE_AA);
  cv::putText(view, text, at, cv::FONT_HERSHEY_SIMPLEX, font, kCentreColor, 2, cv::LINE_AA);
}

}  // namespace

int overlay_scale(cv::Size image) {
  return std::max(1, (kMinOverlayWidthPx + 2 * image.width - 1) / (2 * image.width));
}

cv::Size overlay_size(cv::Size image) {
  const int scale = overlay_scale(image);
  return {2 * image.width * scale, image.height * scale};
}

cv::Mat flow_to_color(const servo::FlowField& flow, double max_magnitude) {
  cv::Mat hsv(flow.height(), flow.width(), CV_8UC3);
  for (int row = 0; row < flow.height(); ++row) {
    auto* out = hsv.ptr<cv::Vec3b>(row);
    for (int col = 0; col < flow.width(); ++col) {
      const Eigen::Vector2f& f = flow.at(col, row);
      if (!f.allFinite()) {
        out[col] = cv::Vec3b(0, 0, 0);
        continue;
      }
      const double angle = std::atan2(f.y(), f.x());
      const double magnitude = f.norm();
      const double value =
          std::isfinite(magnitude) ? std::min(1.0, magnitude / max_magnitude) : 0.0;
      out[col] = cv::Vec3b(static_cast<uchar>((angle + M_PI) / (2.0 * M_PI) * 179.0), 255,
                           static_cast<uchar>(255.0 * value));
    }
  }
  cv::Mat bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr;
}

cv::Mat draw_overlay(const cv::Mat& image, const servo::FlowField& flow,
                     std::span<const servo::ObjectFeatures> objects,
                     const base::CameraIntrinsics& k, std::optional<double> goal_bearing_rad) {
  // Blown up by whole pixels first, then drawn on, so that the marks and the text stay sharp.
  const EnlargedView enlarged{k, overlay_scale(image.size())};
  const cv::Size size = image.size() * enlarged.scale;
  cv::Mat canvas(overlay_size(image.size()), CV_8UC3, cv::Scalar::all(0));
  cv::Mat view = canvas(cv::Rect(0, 0, size.width, size.height));
  cv::resize(image, view, size, 0, 0, cv::INTER_NEAREST);
  cv::resize(flow_to_color(flow, 0.5), canvas(cv::Rect(size.width, 0, size.width, size.height)),
             size, 0, 0, cv::INTER_NEAREST);
  for (const servo::ObjectFeatures& o : objects) {
    draw_object(view, o, enlarged);
  }
  if (goal_bearing_rad) {
    const double bearing = std::clamp(*goal_bearing_rad, -1.5, 1.5);
    const int col = enlarged.px({std::tan(bearing), 0.0}).x;
    if (col >= 0 && col < size.width) {
      cv::line(view, {col, 0}, {col, size.height / 6}, kGoalColor, 4);
    }
  }
  return canvas;
}

std::unique_ptr<cv::VideoWriter> open_video(const std::filesystem::path& path, cv::Size size,
                                            double fps) {
  auto writer = std::make_unique<cv::VideoWriter>(
      path.string(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps, size);
  if (!writer->isOpened()) {
    throw std::runtime_error("cannot write the video " + path.string() +
                             " (OpenCV found no MP4 encoder)");
  }
  return writer;
}

}  // namespace flowsteer::pipeline
