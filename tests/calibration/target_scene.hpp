#pragma once

// Calibration targets rendered by sim_camera: a chessboard standing up or lying on the floor,
// seen by a camera with known intrinsics and a known lens distortion.
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flowsteer/calibration/board.hpp"
#include "flowsteer/camera_io/camera_model.hpp"
#include "flowsteer/sim_camera/renderer.hpp"
#include "flowsteer/sim_camera/world.hpp"

namespace flowsteer::calibration::test {

// The renderer of every test in the process, made on first use (an EGL context is slow to make).
sim_camera::Renderer& shared_renderer();

// The camera the tests calibrate: 640 x 480, non-square pixels, principal point off centre,
// barrel distortion (radial only).
camera_io::CameraModel true_camera();

// The board of the tests: 9 x 6 inner corners, 5 cm squares.
BoardSpec test_board();

// Where a view is taken from: the optical centre, the heading (counter-clockwise from world x)
// and the pitch (positive looks down). No roll: the renderer's cameras have none.
struct CameraPose {
  Eigen::Vector3d eye_m;
  double yaw_rad = 0.0;
  double pitch_rad = 0.0;
};

// The board standing upright, facing -x, and the poses of views around it that tilt it up to
// 35 degrees and bring it to every part of the image.
sim_camera::WorldSpec standing_board_world(const BoardSpec& board);
std::vector<CameraPose> standing_board_views();

// The board lying on the floor, its printed surface `board_top_m` above it.
sim_camera::WorldSpec floor_board_world(const BoardSpec& board, const Eigen::Vector2d& near_edge_m,
                                        double board_top_m);

// Renders what `camera` sees: a pinhole render at twice the resolution, blurred against
// aliasing, resampled through the lens distortion (cv::undistortPoints gives, for each pixel of
// the distorted image, where its ray lands in the pinhole render; cv::remap samples it there).
class DistortedCamera {
 public:
  DistortedCamera(const camera_io::CameraModel& camera, sim_camera::Renderer& renderer);
  cv::Mat render(const sim_camera::World& world, const CameraPose& pose);

 private:
  sim_camera::Renderer& renderer_;
  sim_camera::CameraSpec render_spec_;
  cv::Mat map_x_;
  cv::Mat map_y_;
  sim_camera::RenderedView rendered_;
};

}  // namespace flowsteer::calibration::test
