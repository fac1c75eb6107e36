#include "flowsteer/pipeline/overlay.hpp"

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
}  // namespace

cv::Size overlay_size(cv::Size image) {
  return {2 * image.width, image.height};
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
  const cv::Size size = image.size();
  cv::Mat canvas(overlay_size(size), CV_8UC3, cv::Scalar::all(0));
  cv::Mat view = canvas(cv::Rect(0, 0, size.width, size.height));
  image.copyTo(view);
  flow_to_color(flow, 0.5).copyTo(canvas(cv::Rect(size.width, 0, size.width, size.height)));
  auto to_pixel = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround(k.fx_px * p.x() + k.cx_px)),
                     static_cast<int>(std::lround(k.fy_px * p.y() + k.cy_px)));
  };
  const double font = std::max(0.3, size.width / 400.0);
  for (const servo::ObjectFeatures& o : objects) {
    const cv::Point centre = to_pixel(o.centre);
    cv::circle(view, centre, 3, kCentreColor, cv::FILLED);
    if (o.has_foe()) {
      const cv::Point foe = to_pixel(o.foe);
      cv::circle(view, foe, 4, kFoeColor, 1);
      cv::line(view, foe, centre, kFoeColor, 1);
      char text[32];
      std::snprintf(text, sizeof text, "%.1fs", o.ttc_s);
      cv::putText(view, text, centre + cv::Point(4, -4), cv::FONT_HERSHEY_SIMPLEX, font,
                  kCentreColor, 1);
    }
  }
  if (goal_bearing_rad) {
    const double bearing = std::clamp(*goal_bearing_rad, -1.5, 1.5);
    const int col = static_cast<int>(std::lround(k.fx_px * std::tan(bearing) + k.cx_px));
    if (col >= 0 && col < size.width) {
      cv::line(view, {col, 0}, {col, size.height / 6}, kGoalColor, 2);
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
