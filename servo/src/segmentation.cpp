#include "flowsteer/servo/segmentation.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace flowsteer::servo {

const char* to_string(RegionKind kind) {
  switch (kind) {
    case RegionKind::visible:
      return "visible";
    case RegionKind::dark:
      return "dark";
    case RegionKind::ground:
      return "ground";
    case RegionKind::unconfirmed:
      return "unconfirmed";
  }
  return "unknown";
}

void segment_by_ids(std::span<const std::int32_t> ids, int width, int height,
                    std::span<const std::uint8_t> excluded, Segmentation& out) {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("segment_by_ids: image size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is empty");
  }
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (ids.size() != pixels) {
    throw std::invalid_argument("segment_by_ids: id image has " + std::to_string(ids.size()) +
                                " pixels, expected " + std::to_string(pixels));
  }
  if (!excluded.empty() && excluded.size() != pixels) {
    throw std::invalid_argument("segment_by_ids: exclusion mask has " +
                                std::to_string(excluded.size()) + " pixels, expected " +
                                std::to_string(pixels));
  }
  out.width = width;
  out.height = height;
  out.labels.assign(pixels, Segmentation::kNoRegion);
  out.kinds.clear();
  out.source_ids.clear();

  // Labels are given in order of first appearance. Neighbouring pixels mostly share an id, so
  // the last id seen answers most lookups and the few ids of a frame are searched otherwise:
  // no table sized by the largest id, whatever the ids are.
  std::int32_t last_id = -1;
  std::int32_t last_label = Segmentation::kNoRegion;
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::int32_t id = ids[i];
    if (id < 0 || (!excluded.empty() && excluded[i] != 0)) {
      continue;
    }
    if (id != last_id) {
      const auto known = std::find(out.source_ids.begin(), out.source_ids.end(), id);
      if (known == out.source_ids.end()) {
        out.kinds.push_back(RegionKind::visible);
        out.source_ids.push_back(id);
        last_label = out.region_count() - 1;
      } else {
        last_label = static_cast<std::int32_t>(known - out.source_ids.begin());
      }
      last_id = id;
    }
    out.labels[i] = last_label;
  }
}

}  // namespace flowsteer::servo
