#include "flowsteer/servo/dark_regions.hpp"

#include <cstdint>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace flowsteer::servo {

DarkRegionFinder::DarkRegionFinder(const DarkRegionOptions& options) : options_(options) {
  if (!(options.luminance_threshold > 0.0 && options.luminance_threshold <= 255.0) ||
      !(options.min_area_fraction >= 0.0 && options.min_area_fraction < 1.0)) {
    throw std::invalid_argument(
        "DarkRegionFinder: luminance_threshold must be in (0, 255], min_area_fraction in [0, 1)");
  }
}

int DarkRegionFinder::add_dark_regions(const cv::Mat& grey, Segmentation& out) {
  if (grey.type() != CV_8UC1 || grey.cols != out.width || grey.rows != out.height) {
    throw std::invalid_argument("DarkRegionFinder: expected an 8-bit grey image of " +
                                std::to_string(out.width) + "x" + std::to_string(out.height) +
                                ", got " + cv::typeToString(grey.type()) + " " +
                                std::to_string(grey.cols) + "x" + std::to_string(grey.rows));
  }
  cv::threshold(grey, dark_mask_, options_.luminance_threshold - 1.0, 255.0, cv::THRESH_BINARY_INV);
  // MIG §5 gives every dark pixel the dark label, wherever it is: its flow is not to be trusted,
  // so it leaves the object it belongs to. Above the middle row those pixels then belong to no
  // region. Left in its object, an unlit wall's upper part pulled the wall's FOE fit onto its
  // near-zero flow (an unlit wall 7 m away looked 1.6 s away, on a collision course), and an
  // unlit obstacle stayed a visible one, avoided before any light had reached it.
  const int first_lower_row = grey.rows / 2;
  for (int row = 0; row < first_lower_row; ++row) {
    const std::uint8_t* dark = dark_mask_.ptr<std::uint8_t>(row);
    std::int32_t* labels = out.labels.data() + static_cast<std::size_t>(row) * grey.cols;
    for (int col = 0; col < grey.cols; ++col) {
      if (dark[col] != 0)
        labels[col] = Segmentation::kNoRegion;
    }
  }
  // Only pixels below the middle row can be dark regions. At night the sky and the tops of walls
  // are as dark as the ground ahead; counted in, they join every dark pixel into one component
  // whose centroid lies in the upper half, and the dark ground the agent walks towards is lost
  // with it. Above the middle row nothing is at risk of collision (MIG §5), so those pixels are
  // left out before the components are formed rather than after.
  dark_mask_.rowRange(0, first_lower_row).setTo(0);
  const int components =
      cv::connectedComponentsWithStats(dark_mask_, component_labels_, stats_, centroids_, 8);

  const auto min_area_px = static_cast<int>(options_.min_area_fraction * grey.total());
  region_of_component_.assign(static_cast<std::size_t>(components), Segmentation::kNoRegion);
  right_region_of_component_.assign(static_cast<std::size_t>(components), Segmentation::kNoRegion);
  const auto add_region = [&out] {
    out.kinds.push_back(RegionKind::dark);
    out.source_ids.push_back(-1);
    return out.region_count() - 1;
  };
  int added = 0;
  // Component 0 is the background (the pixels that are not dark).
  for (int c = 1; c < components; ++c) {
    if (stats_.at<int>(c, cv::CC_STAT_AREA) < min_area_px)
      continue;
    const auto k = static_cast<std::size_t>(c);
    region_of_component_[k] = add_region();
    ++added;
    // A component from the left edge of the image to the right one (at night, the unlit ground
    // beyond the light) goes on past both: its centroid is set by the field of view and sits
    // near the heading, on the cusp of exp(−|g|/σ) (MIG Eq. 3), where the sign of g, and with
    // it the turn, flips with noise. Split at the heading (the middle column), it is the dark
    // on either side of the way ahead: two regions whose terms balance when the dark does, and
    // whose difference turns the agent away from the side with more of it.
    const int left = stats_.at<int>(c, cv::CC_STAT_LEFT);
    if (left == 0 && left + stats_.at<int>(c, cv::CC_STAT_WIDTH) == grey.cols) {
      right_region_of_component_[k] = add_region();
      ++added;
    }
  }
  if (added == 0)
    return 0;
  const int middle_col = grey.cols / 2;
  for (int row = first_lower_row; row < grey.rows; ++row) {
    const auto* component = component_labels_.ptr<std::int32_t>(row);
    std::int32_t* labels = out.labels.data() + static_cast<std::size_t>(row) * grey.cols;
    for (int col = 0; col < grey.cols; ++col) {
      const auto k = static_cast<std::size_t>(component[col]);
      std::int32_t region = region_of_component_[k];
      if (col >= middle_col && right_region_of_component_[k] != Segmentation::kNoRegion)
        region = right_region_of_component_[k];
      if (region != Segmentation::kNoRegion)
        labels[col] = region;
    }
  }
  return added;
}

}  // namespace flowsteer::servo
