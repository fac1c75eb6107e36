#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace flowsteer::servo {

// The object-id channel (a rendered frame's object_ids, an analytic scene's ids): ids >= 0 name
// objects; a pixel that hits none is the ground or the sky.
inline constexpr std::int32_t kSkyId = -1;
inline constexpr std::int32_t kGroundId = -2;

// What a region is to the controller: something seen moving (visible), something too dark to
// trust (dark, MIG 2019), the ground, or a region of flow segmentation in the first frame of its
// track (unconfirmed: followed, not yet acted on, FlowSegmentationOptions::confirm_new_regions).
enum class RegionKind : std::uint8_t { visible, dark, ground, unconfirmed };

const char* to_string(RegionKind kind);

// A partition of the image into regions: labels[i] is the region of pixel i (row-major), or
// kNoRegion. Region r has kinds[r] and source_ids[r] (the object id it came from, or -1).
struct Segmentation {
  static constexpr std::int32_t kNoRegion = -1;

  int width = 0;
  int height = 0;
  std::vector<std::int32_t> labels;
  std::vector<RegionKind> kinds;
  std::vector<std::int32_t> source_ids;

  int region_count() const { return static_cast<int>(kinds.size()); }
};

// Semantic segmentation (MIG 2019): one visible region per object id >= 0 in `ids`; negative
// ids (sky, ground) and pixels set in `excluded` (for example the ground mask) belong to no
// region. `excluded` is empty or has one entry per pixel. Reuses out's storage.
void segment_by_ids(std::span<const std::int32_t> ids, int width, int height,
                    std::span<const std::uint8_t> excluded, Segmentation& out);

}  // namespace flowsteer::servo
