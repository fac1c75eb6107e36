#pragma once

#include <opencv2/core.hpp>

#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

struct DarkRegionOptions {
  // A pixel is dark below this grey level (0–255): too dark for its flow to be trusted.
  double luminance_threshold = 80.0;
  // Dark regions smaller than this fraction of the image are dropped (MIG §5: noise, small
  // shadows).
  double min_area_fraction = 0.003;
};

// Dark regions (MIG 2019 §5): every dark pixel leaves whatever region it was in, since its flow
// is not to be trusted. Each connected set of dark pixels in the lower half of the image (the
// upper half is sky and the tops of walls, not the way ahead; a night sky would otherwise join
// all dark pixels into one region) that is large enough becomes a region of kind dark, appended
// to `out`; one that reaches both sides of the image becomes two, split at the middle column.
// Dark pixels of the upper half belong to no region. `grey` is 8-bit with out's size.
class DarkRegionFinder {
 public:
  explicit DarkRegionFinder(const DarkRegionOptions& options = {});

  // Returns how many dark regions were added.
  int add_dark_regions(const cv::Mat& grey, Segmentation& out);

 private:
  DarkRegionOptions options_;
  cv::Mat dark_mask_;
  cv::Mat component_labels_;
  cv::Mat stats_;
  cv::Mat centroids_;
  std::vector<std::int32_t> region_of_component_;
  std::vector<std::int32_t> right_region_of_component_;  // split components' right half
};

}  // namespace flowsteer::servo
