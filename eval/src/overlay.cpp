#include "flowsteer/eval/overlay.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

namespace flowsteer::eval {

namespace {

const cv::Scalar kFoeColor(255, 120, 0);
const cv::Scalar kCentreColor(0, 140, 255);
const cv::Scalar kGoalColor(200, 80, 255);
constexpr int kCaptionFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kCaptionScale = 0.55;
constexpr int kCaptionMargin = 8;  // px, left of the top view's caption and at least as much right

cv::Scalar agent_color(std::size_t i) {
  static const cv::Scalar palette[] = {{200, 60, 30},  {40, 160, 40},  {30, 60, 220},
                                       {180, 40, 180}, {20, 170, 200}, {120, 90, 20},
                                       {90, 90, 90},   {60, 200, 140}};
  return palette[i % std::size(palette)];
}

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

cv::Mat draw_overlay(const SimulatedAgent& agent) {
  const pipeline::Brain& brain = agent.brain();
  return draw_overlay(agent.frame().image, brain.perception().flow(), brain.objects(),
                      agent.intrinsics(), brain.percept().goal_bearing_rad);
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

cv::Mat draw_topview(const sim_camera::World& world,
                     const std::vector<std::vector<Eigen::Vector2d>>& paths,
                     const std::vector<sim_camera::Collision>& collisions) {
  const sim_camera::WorldSpec& spec = world.spec();
  Eigen::AlignedBox2d bounds;
  for (const auto& path : paths) {
    for (const auto& p : path) {
      bounds.extend(p);
    }
  }
  for (const auto& a : spec.agents) {
    bounds.extend(a.start_m);
    for (const auto& g : a.goals) {
      bounds.extend(g);
    }
  }
  for (const auto& o : spec.obstacles) {
    if (o.shape == sim_camera::Solid::Shape::box) {
      for (const Eigen::Vector2d& corner : sim_camera::box_corners(o)) {
        bounds.extend(corner);
      }
    } else {
      bounds.extend(o.centre_m - Eigen::Vector2d(o.radius_m, o.radius_m));
      bounds.extend(o.centre_m + Eigen::Vector2d(o.radius_m, o.radius_m));
    }
  }
  const Eigen::Vector2d margin(1.5, 1.5);
  const Eigen::Vector2d lo = bounds.min() - margin;
  const Eigen::Vector2d extent = bounds.max() + margin - lo;
  const double scale = 900.0 / std::max(extent.x(), extent.y());
  char caption[160];
  std::snprintf(caption, sizeof caption, "%s  t = %.1f s  collisions: %zu  (1 m = %.0f px)",
                spec.name.c_str(), world.time_s(), collisions.size(), scale);
  const int caption_width = cv::getTextSize(caption, kCaptionFont, kCaptionScale, 1, nullptr).width;
  // A narrow world (a corridor) is centred in an image wide enough for the caption.
  const int world_width = static_cast<int>(extent.x() * scale);
  const cv::Size size(std::max(world_width, caption_width + 2 * kCaptionMargin),
                      static_cast<int>(extent.y() * scale) + 30);
  const int left = (size.width - world_width) / 2;
  cv::Mat image(size, CV_8UC3, cv::Scalar(250, 250, 250));
  // World y points up in the picture.
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(left + static_cast<int>((p.x() - lo.x()) * scale),
                     static_cast<int>(size.height - 30 - (p.y() - lo.y()) * scale));
  };
  auto draw_solid = [&](const sim_camera::Solid& s, const cv::Scalar& color, int thickness) {
    if (s.shape == sim_camera::Solid::Shape::cylinder) {
      cv::circle(image, px(s.centre_m), static_cast<int>(s.radius_m * scale), color, thickness,
                 cv::LINE_AA);
      return;
    }
    std::vector<cv::Point> corners;
    for (const Eigen::Vector2d& corner : sim_camera::box_corners(s)) {
      corners.push_back(px(corner));
    }
    if (thickness == cv::FILLED) {
      cv::fillConvexPoly(image, corners, color, cv::LINE_AA);
    } else {
      cv::polylines(image, corners, true, color, thickness, cv::LINE_AA);
    }
  };
  for (const auto& o : spec.obstacles) {
    draw_solid(o, cv::Scalar(150, 150, 150), cv::FILLED);
  }
  for (std::size_t k = 0; k < spec.moving.size(); ++k) {
    const auto& m = spec.moving[k];
    for (std::size_t w = 1; w < m.waypoints.size(); ++w) {
      cv::line(image, px(m.waypoints[w - 1]), px(m.waypoints[w]), cv::Scalar(200, 200, 200), 1);
    }
    draw_solid(world.moving_now(k), cv::Scalar(110, 110, 110), 2);
  }
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const cv::Scalar color = agent_color(i);
    const auto& path = paths[i];
    for (std::size_t k = 1; k < path.size(); ++k) {
      cv::line(image, px(path[k - 1]), px(path[k]), color, 2, cv::LINE_AA);
    }
    const auto& agent = spec.agents[i];
    cv::circle(image, px(agent.start_m), static_cast<int>(agent.radius_m * scale), color, 1,
               cv::LINE_AA);
    if (!path.empty()) {
      cv::circle(image, px(path.back()), static_cast<int>(agent.radius_m * scale), color,
                 cv::FILLED, cv::LINE_AA);
    }
    for (const auto& g : agent.goals) {
      cv::drawMarker(image, px(g), color, cv::MARKER_CROSS, 14, 2);
    }
  }
  for (const auto& c : collisions) {
    cv::drawMarker(image, px(c.position_m), cv::Scalar(0, 0, 255), cv::MARKER_TILTED_CROSS, 18, 3);
  }
  cv::putText(image, caption, {kCaptionMargin, size.height - 10}, kCaptionFont, kCaptionScale,
              cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  return image;
}

}  // namespace flowsteer::eval
