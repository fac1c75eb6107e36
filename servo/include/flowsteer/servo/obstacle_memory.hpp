#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/features.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/segmentation.hpp"

namespace flowsteer::servo {

struct ObstacleMemoryOptions {
  // An observation closer than this to a remembered point is that point: the memory's
  // resolution, one point every spacing_m along a wall.
  double spacing_m = 0.1;
  // Recalled points closer than this to each other are one object: a wall is one.
  double link_m = 0.3;
  double range_m = 4.0;   // points further away are dropped
  double behind_m = 0.5;  // points further behind the camera than this are dropped
  // A point whose spot shows the floor, where it should be seen, for this long in all since it
  // was last observed is dropped: the obstacle has gone.
  double fade_s = 1.5;
  // A point seen once is dropped unless it is seen again within this: one frame's phantom is
  // not remembered.
  double confirm_s = 0.5;
  // A point is confirmed (recalled, kept past confirm_s) once its sightings span this long and
  // stay within spacing_m of its first: what walks by faster than spacing_m / confirm_span_s
  // (0.4 m/s), such as a person whose plain clothes the untextured fill gave a static point's
  // flow, leaves a trail of points none of which is confirmed.
  double confirm_span_s = 0.25;
  // Any point not seen for this long is dropped: out of view nothing says that what stood there
  // still does (people stand, then walk on), and a wall passed at walking speed is behind by then.
  double forget_s = 3.0;
  // A ground contact of a region with the static FOE is taken where the region's fitted τ puts
  // a static point within this fraction of the contact's depth: someone walking towards the
  // agent has the static FOE too, and a τ a fraction of that; and a region that took in floor
  // below what stands there has contacts nearer than its τ says.
  double ttc_tolerance = 0.25;
  // A contact is also taken where its region's pixels in its column, over this height above
  // the foot, move as an upright surface standing there would and not as the floor: a wall
  // along the course, whose one τ spans the depths of all its contacts. Only rows where the two
  // differ by more than the flow's error count: near the foot, or far ahead, they do not.
  double column_height_m = 1.0;
  // The measured flow's error in the column's test, in pixels over the flow's interval, beside
  // ttc_tolerance of the flow.
  double column_flow_error_px = 0.5;
  // Below this speed nothing expands, and no region can be told to stand still.
  double min_speed_mps = 0.1;
  // The floor must show over this height above a point's foot to count against the point; an
  // obstacle's lowest rows move nearly as the floor does, and the ground test takes some of them.
  double evidence_height_m = 0.3;
  // Recalled points nearer the camera's plane than this have no usable image bearing.
  double min_forward_m = 0.05;
  int capacity = 512;  // points at most; observations beyond it are not remembered
};

// A short-term memory of what stood still around the agent (NanoMap, Florence et al. 2018, in
// spirit): the ground contacts of static regions, as points on the ground in the body frame
// (x forward, y left, metres; CONVENTIONS.md), carried by odometry, and recalled as objects where
// the view no longer shows them: a wall whose foot has left the view, a pillar beside the agent.
// Keeps its buffers from frame to frame; one per agent.
class ObstacleMemory {
 public:
  // Source ids of recalled objects start here, clear of the renderer's and of FlowSegmenter's
  // kFirstTrackId range.
  static constexpr std::int32_t kFirstId = 1 << 28;

  struct Point {
    Eigen::Vector2d position_m = Eigen::Vector2d::Zero();    // body frame
    Eigen::Vector2d first_seen_m = Eigen::Vector2d::Zero();  // where it was first seen, carried
    std::int32_t id = kFirstId;
    int sightings = 0;            // frames it was observed in
    double age_s = 0.0;           // since it was first observed
    double unseen_s = 0.0;        // since it was last observed
    double contradicted_s = 0.0;  // of unseen_s, the time its spot showed the floor
    enum class Sight : std::uint8_t {
      observed,      // a static region stands there this frame
      covered,       // a region covers its spot: that region is the percept's
      contradicted,  // its spot shows the floor
      unknown,       // in the image, but neither floor nor a region shows there: kept, as seen
      out_of_view,   // its foot is outside the image, or behind the camera
    } sight = Sight::out_of_view;
  };

  // What one frame shows: the derotated field (its geometry), the segmentation, the ground
  // mask (1 where a pixel matched the flat ground; empty or one entry per pixel), and the
  // features (in label order) and ground contacts extracted from them.
  struct View {
    const FlowField& field;
    const Segmentation& segmentation;
    std::span<const std::uint8_t> ground_mask;
    std::span<const ObjectFeatures> objects;
    std::span<const GroundContact> contacts;
  };

  explicit ObstacleMemory(const base::CameraMount& mount,
                          const ObstacleMemoryOptions& options = {});

  // Moves the points by the agent's motion over dt_s at a constant speed_mps and turn_rate
  // (positive right, CONVENTIONS.md): the exact arc of a unicycle. Drops the points it takes out
  // of range or behind.
  void carry(double speed_mps, double turn_rate, double dt_s);
  // Adds the ground contacts of the regions that stand still (the agent moving at speed_mps over
  // the flow's interval), counts the frame against the points not observed, and drops those
  // faded or never confirmed; dt_s since the last call.
  void observe(const View& view, double speed_mps, double dt_s);
  // The confirmed points whose feet the last observed view does not show (beside or behind the
  // camera, below the image), linked into objects as the law reads any object: the polyline through
  // their leftmost, nearest and rightmost points, static (the static FOE, τ = Z / v at the
  // nearest depth along the course). Valid until the next call.
  std::span<const ObjectFeatures> recall(double speed_mps);

  std::span<const Point> points() const { return points_; }
  // Whether a point has been seen standing still long enough to be recalled and kept.
  bool confirmed(const Point& point) const {
    return point.sightings >= 2 && point.age_s - point.unseen_s >= options_.confirm_span_s;
  }

 private:
  // Whether the contact is where a region that stands still stands.
  bool stands_still(const View& view, const GroundContact& contact, double speed_mps) const;
  // Whether the contact's column moves as an upright surface standing at its foot.
  bool column_stands_upright(const View& view, const GroundContact& contact,
                             double speed_mps) const;
  void remember(const Eigen::Vector2d& position_m);
  Point::Sight sight_of(const View& view, const Point& point) const;
  std::size_t find(std::size_t i);  // the root of i's object in parent_

  ObstacleMemoryOptions options_;
  FlatGround ground_;
  Eigen::Vector2d static_foe_;
  double cos_pitch_;
  std::vector<Point> points_;
  std::int32_t next_id_ = kFirstId;
  std::vector<std::size_t> recalled_;  // indices into points_
  std::vector<std::size_t> parent_;    // union-find over recalled_
  std::vector<int> object_of_;         // per root, its object in objects_
  std::vector<ObjectFeatures> objects_;
};

}  // namespace flowsteer::servo
