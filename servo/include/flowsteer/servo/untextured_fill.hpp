#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/flow_field.hpp"

namespace flowsteer::servo {

struct UntexturedFillOptions {
  bool enabled = true;
  // The floor, scanned up a column, is pixels without flow or ground, with gaps of up to this many
  // pixels with flow of their own: the estimators leave specks of flow on a plain floor.
  int contact_search_px = 3;
  // A surface is filled only where at least this share of its column between foot and top has
  // no flow: far floor between a mark on it and the horizon has texture.
  double min_untextured_share = 0.8;
  // A surface's foot is where the floor's grey level steps by at least this much across two
  // rows, scanning up from the floor.
  double min_edge_grey = 4.0;
  // Feet farther ahead than this are not filled: their flow is below what the estimators resolve,
  // and the sky seen over far ground would pass for a wall there.
  double max_distance_ahead_m = 6.0;
};

// Gives flow to untextured surfaces that stand on the ground. Numerical flow has none on a plain
// wall, door or pillar (the texture test drops what the estimators would invent there), so
// without this a robot sees through them. Scanning a column up from the image's bottom, the floor
// (pixels without flow, or ground) ends at its last grey-level edge below the horizon: the foot of
// a surface, if above it the column has no flow up to the surface's own top edge above the
// horizon (a surface taller than the camera). Every pixel of it without flow is as far ahead as
// that foot, and gets the flow the measured ego-motion gives a static point there (depth from
// derotated flow and known speed, McCarthy, Barnes and Srinivasan, ICRA 2007, used the other way
// round). A wall whose foot is out of view, a box lower than the camera and a plain floor get
// nothing. Keeps its buffers from frame to frame.
class UntexturedFill {
 public:
  explicit UntexturedFill(const UntexturedFillOptions& options = {}) : options_(options) {}

  // `derotated` is numerical flow, NaN where it has none; ground_mask marks its ground pixels
  // (mark_ground). speed_mps is the base's over the field's interval. Returns the pixels filled.
  int fill(FlowField& derotated, const cv::Mat& grey, double image_noise_grey,
           const base::CameraMount& mount, double speed_mps,
           std::span<const std::uint8_t> ground_mask);

  // One entry per pixel of the last field filled: 1 where fill() gave the flow.
  std::span<const std::uint8_t> filled() const { return filled_; }

 private:
  void find_feet(const FlowField& field, const cv::Mat& grey, const base::CameraMount& mount,
                 std::span<const std::uint8_t> ground_mask);
  int find_foot(const FlowField& field, const cv::Mat& grey,
                std::span<const std::uint8_t> ground_mask, int col, int first_ground_row) const;
  bool is_edge(const cv::Mat& grey, int col, int row) const;
  int lowest_edge(const cv::Mat& grey, int col, int top, int bottom) const;

  UntexturedFillOptions options_;
  double edge_threshold_ = 0.0;          // grey levels per column, this frame's
  std::vector<float> inverse_distance_;  // per pixel, 1 / metres ahead; 0 where not filled
  std::vector<std::uint8_t> filled_;
};

}  // namespace flowsteer::servo
