#pragma once

#include <array>
#include <cstdint>
#include <ostream>
#include <vector>

#include <opencv2/core.hpp>

#include "flowsteer/calibration/board.hpp"
#include "flowsteer/camera_io/frame_source.hpp"

namespace flowsteer::calibration {

struct CaptureOptions {
  int views = 15;         // stop once this many views are kept
  int max_frames = 3000;  // and give up after this many frames
  double read_timeout_s = 1.0;
  double stall_s = 10.0;  // a camera silent this long is an error
  // A view is kept when its board covers this many cells of an 8 x 6 grid no kept view
  // covered, or when its pose differs from every kept view's by this much (see pose_of).
  int min_new_cells = 2;
  double min_pose_distance = 0.2;
};

// What the board's outline says about the view: where its centre is in the image (fractions of
// the width and height), how big it is (square root of its share of the image) and how it is
// tilted (twice how much longer one side is than the opposite one, left/right, top/bottom). Views
// far apart in these numbers constrain the calibration differently (the criterion of ROS's
// camera_calibration).
using BoardPose = std::array<double, 5>;
BoardPose pose_of(const BoardView& view, cv::Size image_size);

struct CapturedView {
  cv::Mat image;  // a copy: the source's buffers are only valid until its next read
  BoardView board;
  std::uint64_t sequence = 0;
};

struct CaptureResult {
  std::vector<CapturedView> views;
  int frames = 0;
  int frames_with_board = 0;
  cv::Size image_size;  // of the frames read; empty when none was
  bool source_ended = false;
};

// Reads frames (which must be the camera's raw, distorted images) until options.views views
// are kept, the source ends or options.max_frames frames were read. Logs each kept view.
// Throws std::runtime_error when the source stalls.
CaptureResult capture_views(camera_io::FrameSource& source, const BoardDetector& detector,
                            const CaptureOptions& options, std::ostream& log);

}  // namespace flowsteer::calibration
