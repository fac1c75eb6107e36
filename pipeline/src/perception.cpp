#include "perception.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "flowsteer/base/clock.hpp"
#include "motion_history.hpp"

namespace flowsteer::pipeline {

namespace {

bool synthetic(const PerceptionOptions& options) {
  return options.flow == servo::FlowMethod::synthetic;
}

servo::FeatureOptions feature_options(const PerceptionOptions& options,
                                      const servo::FlowSource& flow) {
  servo::FeatureOptions features;
  features.use_depth = per_pixel_depth(options);
  // A camera has no depth; where objects stand on the ground, the ground gives it.
  if (!features.use_depth) {
    features.ground_mount = options.mount;
  }
  features.static_foe = options.mount.forward_foe();
  features.flow_noise_correlation_px = flow.noise_correlation_px();
  return features;
}

// The fill's floor scan passes the band of flow an estimator spreads along a foot's edge.
servo::UntexturedFillOptions fill_options(const PerceptionOptions& options,
                                          const servo::FlowSource& flow) {
  servo::UntexturedFillOptions fill = options.untextured_fill;
  fill.flow_spread_px = 0.5 * flow.noise_correlation_px();
  return fill;
}

}  // namespace

StageTimes& StageTimes::operator+=(const StageTimes& other) {
  render += other.render;
  flow += other.flow;
  segment += other.segment;
  features += other.features;
  control += other.control;
  total += other.total;
  return *this;
}

Perception::Perception(const base::CameraIntrinsics& intrinsics, const PerceptionOptions& options)
    : options_(options),
      field_(intrinsics, per_pixel_depth(options)),
      // With the ground's depth only, the sky has no flow either, as a camera's has none.
      flow_source_(servo::make_flow_source(
          options.flow, options.optical_flow,
          {.no_flow_without_depth = options.depth == servo::DepthSource::ground})),
      untextured_fill_(fill_options(options, *flow_source_)),
      dark_finder_(options.dark),
      extractor_(feature_options(options, *flow_source_)),
      motions_(std::make_unique<MotionHistory>(
          static_cast<std::size_t>(options.optical_flow.max_kept_images) + 2)) {
  if (options.segmentation != servo::SegmentationMethod::semantic) {
    segmenter_.emplace(options.segmentation, options.flow_segmentation);
  }
  if (options.obstacle_memory) {
    // Its points are ground contacts, which only flow segmentation without depth gives.
    if (!segmenter_ || per_pixel_depth(options)) {
      throw std::invalid_argument(
          "Perception: the obstacle memory needs flow segmentation without the renderer's depth");
    }
    memory_.emplace(options.mount, options.memory);
  }
}

bool Perception::reads_image() const {
  return flow_source_->estimated() || options_.dark_regions || segments_by_grey();
}

bool Perception::segments_by_grey() const {
  return segmenter_ && options_.flow_segmentation.grey_weight > 0.0;
}

servo::FlowStatus Perception::process(const camera_io::Frame& frame, double speed_mps,
                                      double turn_rate_cy, StageTimes& times) {
  objects_ = {};
  const bool needs_sim =
      synthetic(options_) || options_.segmentation == servo::SegmentationMethod::semantic;
  if (needs_sim && !frame.sim) {
    throw std::invalid_argument(
        std::string("Perception: ") +
        (synthetic(options_) ? "synthetic flow" : "semantic segmentation") +
        " needs a simulator's frames; a camera or a recording needs numerical flow and flow "
        "segmentation");
  }

  base::Stopwatch stage;
  const MotionHistory::Motion measured{speed_mps, turn_rate_cy};
  motions_->remember(frame.timestamp_s, measured);
  const cv::Mat& image = frame.image;
  // Grey for the fill, the segmentation and the dark regions: an estimator converts the frame into
  // the grey image it keeps, and a grey image handed to it is copied (which costs less than
  // converting twice).
  const bool needs_grey = !image.empty() && reads_image();
  if (needs_grey) {
    if (image.channels() == 3) {
      cv::cvtColor(image, grey_, cv::COLOR_BGR2GRAY);
    } else {
      image.copyTo(grey_);
    }
  }
  const cv::Mat& flow_image = needs_grey ? grey_ : image;
  const servo::FlowFrame flow_frame{flow_image, frame.timestamp_s,
                                    frame.sim ? &frame.sim->flow : nullptr,
                                    frame.sim ? &frame.sim->depth_m : nullptr};
  // The estimators turn the older image by the mean turn rate over their baseline and test the
  // floor's motion over the distance driven in it; the renderer's flow is derotated by this
  // frame's turn rate.
  const auto mean_motion = [&](double from_s, double to_s) {
    return motions_->mean(from_s, to_s, measured);
  };
  const servo::CameraMotion motion{
      servo::camera_angular_velocity(turn_rate_cy, options_.mount.pitch_rad),
      [&](double from_s, double to_s) {
        return servo::rotation_over(
            servo::camera_angular_velocity(mean_motion(from_s, to_s).turn_rate_cy,
                                           options_.mount.pitch_rad),
            to_s - from_s);
      },
      [&](double from_s, double to_s) {
        const MotionHistory::Motion mean = mean_motion(from_s, to_s);
        // turn_rate_cy is positive to the right; the travel's turn, to the left.
        return servo::BaseTravel{mean.speed_mps * (to_s - from_s),
                                 -mean.turn_rate_cy * (to_s - from_s)};
      },
      options_.mount};
  status_ = flow_source_->update(flow_frame, motion, field_);
  times.flow = stage.elapsed_ms();
  if (status_ != servo::FlowStatus::ok)
    return status_;

  stage.restart();
  // What the flow shows moved at the base's mean speed over the flow's interval: at the 1 m/s² an
  // agent brakes or speeds up with, the speed at its end is 10% off that.
  const double flow_speed_mps =
      motions_->mean(frame.timestamp_s - field_.interval_s(), frame.timestamp_s, measured)
          .speed_mps;
  if (segmenter_) {
    ground_mask_.assign(field_.size(), 0);
    servo::GroundRemovalOptions ground = options_.ground;
    if (flow_source_->estimated()) {
      ground.flow_floor =
          std::max(ground.flow_floor, options_.numerical_flow_noise_px /
                                          (field_.intrinsics().fx_px * field_.interval_s()));
    }
    servo::mark_ground(field_, options_.mount, flow_speed_mps, ground, ground_mask_);
    if (flow_source_->estimated()) {
      untextured_fill_.fill(field_, grey_, flow_source_->image_noise_grey(), options_.mount,
                            flow_speed_mps, ground_mask_, flow_source_->edge_flow());
    }
    // The segmenter follows each region back along its flow and the turn to the previous frame.
    servo::ViewMotion view_motion;
    if (segmented_at_s_) {
      view_motion = {servo::camera_angular_velocity(turn_rate_cy, options_.mount.pitch_rad),
                     frame.timestamp_s - *segmented_at_s_};
    }
    segmented_at_s_ = frame.timestamp_s;
    segmenter_->segment(field_, ground_mask_, needs_grey && segments_by_grey() ? grey_ : cv::Mat(),
                        segmentation_, view_motion);
    if (flow_source_->estimated()) {
      ground_regions_.mark(field_, options_.mount, flow_speed_mps, ground, segmentation_);
    }
  } else {
    // The renderer's ground id already marks the ground.
    const cv::Mat& ids = frame.sim->object_ids;
    servo::segment_by_ids({ids.ptr<std::int32_t>(), ids.total()}, ids.cols, ids.rows, {},
                          segmentation_);
  }
  if (options_.dark_regions)
    dark_finder_.add_dark_regions(grey_, segmentation_);
  times.segment = stage.elapsed_ms();

  stage.restart();
  // What stands still closes in at the camera's speed along its optical axis
  // (FeatureExtractor::extract's depths from flow).
  objects_ = extractor_.extract(field_, segmentation_,
                                flow_speed_mps * std::cos(options_.mount.pitch_rad));
  if (memory_) {
    objects_ = with_remembered(frame.timestamp_s, speed_mps, turn_rate_cy, flow_speed_mps);
  }
  times.features = stage.elapsed_ms();
  return status_;
}

std::span<const servo::ObjectFeatures> Perception::with_remembered(double timestamp_s,
                                                                   double speed_mps,
                                                                   double turn_rate_cy,
                                                                   double flow_speed_mps) {
  const MotionHistory::Motion measured{speed_mps, turn_rate_cy};
  // Carried by what the base measured since the memory last saw a frame, which a frame without
  // flow may have made longer than one frame.
  const double since_s = memory_time_s_.value_or(timestamp_s);
  const MotionHistory::Motion moved = motions_->mean(since_s, timestamp_s, measured);
  memory_->carry(moved.speed_mps, moved.turn_rate_cy, timestamp_s - since_s);
  memory_time_s_ = timestamp_s;
  memory_->observe({field_, segmentation_, ground_mask_, objects_, extractor_.contacts()},
                   flow_speed_mps, timestamp_s - since_s);
  const auto recalled = memory_->recall(speed_mps);
  percept_objects_.assign(objects_.begin(), objects_.end());
  percept_objects_.insert(percept_objects_.end(), recalled.begin(), recalled.end());
  return percept_objects_;
}

void MotionHistory::remember(double timestamp_s, const Motion& motion) {
  if (count_ == samples_.size()) {
    begin_ = (begin_ + 1) % samples_.size();
    --count_;
  }
  samples_[(begin_ + count_) % samples_.size()] = {timestamp_s, motion};
  ++count_;
}

MotionHistory::Motion MotionHistory::mean(double from_s, double to_s,
                                          const Motion& fallback) const {
  Motion sum{0.0, 0.0};
  double covered_s = 0.0;
  for (std::size_t k = 1; k < count_; ++k) {
    const double start = std::max(at(k - 1).timestamp_s, from_s);
    const double end = std::min(at(k).timestamp_s, to_s);
    if (end > start) {
      sum.speed_mps += at(k).motion.speed_mps * (end - start);
      sum.turn_rate_cy += at(k).motion.turn_rate_cy * (end - start);
      covered_s += end - start;
    }
  }
  if (!(covered_s > 0.0)) {
    return fallback;
  }
  return {sum.speed_mps / covered_s, sum.turn_rate_cy / covered_s};
}

Perception::~Perception() = default;

}  // namespace flowsteer::pipeline
