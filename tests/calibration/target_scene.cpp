#include "target_scene.hpp"

#include <cmath>
#include <memory>
#include <numbers>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace flowsteer::calibration::test {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
// Render this many times finer than the calibrated camera, then blur: smooth, unaliased edges.
constexpr double kSupersample = 2.0;

// The board's plane and extent for the standing board: x = kBoardX, squares aligned with the
// renderer's world-space checker pattern (edges on multiples of the square size; the plane
// half a square off one, so the pattern does not flicker on it).
constexpr double kBoardX = 40.5;     // in squares
constexpr double kBoardBottom = 20;  // in squares above the floor

sim_camera::Material white() {
  sim_camera::Material m;
  m.albedo = {1.0F, 1.0F, 1.0F};
  m.pattern = sim_camera::Material::Pattern::plain;
  m.pattern_contrast = 0.0F;
  return m;
}

sim_camera::Material checker(double square_m) {
  sim_camera::Material m = white();
  m.pattern = sim_camera::Material::Pattern::checker;
  m.pattern_scale_m = static_cast<float>(square_m);
  m.pattern_contrast = 1.0F;
  return m;
}

sim_camera::Solid box(Eigen::Vector2d centre, Eigen::Vector2d size, double height,
                      sim_camera::Material material) {
  sim_camera::Solid s;
  s.shape = sim_camera::Solid::Shape::box;
  s.centre_m = centre;
  s.size_m = size;
  s.height_m = height;
  s.material = material;
  return s;
}

// Flat light: no sun and no shadows, so that the squares are pure black and white.
sim_camera::WorldSpec empty_world() {
  sim_camera::WorldSpec w;
  w.name = "calibration target";
  w.lighting.ambient = 1.0F;
  w.lighting.sun.reset();
  w.ground.albedo = {0.35F, 0.35F, 0.35F};
  w.ground.pattern = sim_camera::Material::Pattern::plain;
  sim_camera::AgentSpec bystander;  // a world needs an agent: one far behind every camera
  bystander.name = "bystander";
  bystander.start_m = {-30.0, 0.0};
  bystander.goals = {{-31.0, 0.0}};
  w.agents.push_back(bystander);
  return w;
}

}  // namespace

camera_io::CameraModel true_camera() {
  camera_io::CameraModel m;
  m.width_px = 640;
  m.height_px = 480;
  m.fx = 520.0;
  m.fy = 516.0;
  m.cx = 331.5;
  m.cy = 236.0;
  m.distortion = camera_io::DistortionModel::plumb_bob;
  m.coefficients = {-0.25, 0.08, 0.0, 0.0, 0.0};
  return m;
}

BoardSpec test_board() {
  return BoardSpec::parse("chessboard:9x6:0.05");
}

sim_camera::WorldSpec standing_board_world(const BoardSpec& board) {
  const double s = board.square_m;
  const double width = (board.cols + 1) * s;
  const double height = (board.rows + 1) * s;
  const double x = kBoardX * s;
  const double bottom = kBoardBottom * s;
  const double thin = 0.002;
  sim_camera::WorldSpec w = empty_world();
  // The checkered face at x; white behind it (the border at the sides and the top) and in
  // front of it below the board (the bottom border and the stand).
  w.obstacles.push_back(box({x + 0.5 * thin, 0.0}, {thin, width}, bottom + height, checker(s)));
  w.obstacles.push_back(
      box({x + 1.5 * thin, 0.0}, {thin, width + 2 * s}, bottom + height + s, white()));
  w.obstacles.push_back(box({x - 0.5 * thin, 0.0}, {thin, width + 2 * s}, bottom, white()));
  return w;
}

std::vector<CameraPose> standing_board_views() {
  const BoardSpec board = test_board();
  const double s = board.square_m;
  const Eigen::Vector3d centre(kBoardX * s, 0.0, (kBoardBottom + 0.5 * (board.rows + 1)) * s);
  // Around the board: azimuth and elevation of the camera seen from the board, distance, and
  // where the camera looks away from the board's centre (moving the board in the image).
  struct Placement {
    double azimuth_deg, elevation_deg, distance_m, look_left_deg, look_down_deg;
  };
  const Placement placements[] = {
      {0, 0, 1.1, 0, 0},       {30, 0, 1.1, 0, 0},      {-30, 0, 1.1, 0, 0},
      {0, 25, 1.1, 0, 0},      {0, -20, 1.1, 0, 0},     {20, 15, 0.9, 18, 12},
      {-20, 15, 0.9, -18, 12}, {20, -15, 0.9, 18, -12}, {-20, -15, 0.9, -18, -12},
      {35, 10, 1.0, -13, 0},   {-35, -10, 1.0, 13, 0},  {10, 30, 1.0, 0, 11},
      {-10, -25, 1.0, 0, -11}, {25, 20, 1.3, 16, -10},  {-25, -5, 1.3, -16, 10},
  };
  std::vector<CameraPose> poses;
  for (const Placement& p : placements) {
    const double az = p.azimuth_deg * kDeg;
    const double el = p.elevation_deg * kDeg;
    const Eigen::Vector3d eye =
        centre + p.distance_m * Eigen::Vector3d(-std::cos(el) * std::cos(az),
                                                std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Vector3d to_board = centre - eye;
    CameraPose pose;
    pose.eye_m = eye;
    pose.yaw_rad = std::atan2(to_board.y(), to_board.x()) + p.look_left_deg * kDeg;
    pose.pitch_rad = std::atan2(-to_board.z(), to_board.head<2>().norm()) + p.look_down_deg * kDeg;
    poses.push_back(pose);
  }
  return poses;
}

sim_camera::WorldSpec floor_board_world(const BoardSpec& board, const Eigen::Vector2d& near_edge_m,
                                        double board_top_m) {
  const double s = board.square_m;
  // The board's rows run along y, its columns along x; its edges on multiples of the square.
  const Eigen::Vector2d size((board.rows + 1) * s, (board.cols + 1) * s);
  const Eigen::Vector2d corner(std::round(near_edge_m.x() / s) * s,
                               std::round(near_edge_m.y() / s) * s - 0.5 * size.y());
  const Eigen::Vector2d centre = corner + 0.5 * size;
  sim_camera::WorldSpec w = empty_world();
  w.obstacles.push_back(box(centre, size, board_top_m, checker(s)));
  w.obstacles.push_back(
      box(centre, size + Eigen::Vector2d(2 * s, 2 * s), 0.5 * board_top_m, white()));
  return w;
}

sim_camera::Renderer& shared_renderer() {
  static const std::unique_ptr<sim_camera::Renderer> renderer = sim_camera::Renderer::create();
  return *renderer;
}

DistortedCamera::DistortedCamera(const camera_io::CameraModel& camera,
                                 sim_camera::Renderer& renderer)
    : renderer_(renderer) {
  // Each pixel of the distorted image, as a normalised ray of the pinhole camera.
  std::vector<cv::Point2f> pixels;
  for (int row = 0; row < camera.height_px; ++row) {
    for (int col = 0; col < camera.width_px; ++col) {
      pixels.emplace_back(static_cast<float>(col), static_cast<float>(row));
    }
  }
  std::vector<cv::Point2f> rays;
  const cv::TermCriteria exact(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12);
  if (camera.distortion == camera_io::DistortionModel::equidistant) {
    cv::fisheye::undistortPoints(pixels, rays, camera.camera_matrix(), camera.coefficients,
                                 cv::noArray(), cv::noArray(), exact);
  } else {
    cv::undistortPoints(pixels, rays, camera.camera_matrix(), camera.coefficients, cv::noArray(),
                        cv::noArray(), exact);
  }
  double reach_x = 0.0;
  double reach_y = 0.0;
  for (const cv::Point2f& r : rays) {
    reach_x = std::max(reach_x, std::abs(static_cast<double>(r.x)));
    reach_y = std::max(reach_y, std::abs(static_cast<double>(r.y)));
  }
  // A square-pixel pinhole render, centred, that reaches every ray with a few pixels to spare.
  const double f = kSupersample * std::max(camera.fx, camera.fy);
  render_spec_.width_px = 2 * static_cast<int>(std::ceil(f * reach_x)) + 8;
  render_spec_.height_px = 2 * static_cast<int>(std::ceil(f * reach_y)) + 8;
  render_spec_.hfov_rad = 2.0 * std::atan(0.5 * render_spec_.width_px / f);
  const double cx = 0.5 * (render_spec_.width_px - 1);
  const double cy = 0.5 * (render_spec_.height_px - 1);
  map_x_.create(camera.height_px, camera.width_px, CV_32FC1);
  map_y_.create(camera.height_px, camera.width_px, CV_32FC1);
  for (int row = 0; row < camera.height_px; ++row) {
    for (int col = 0; col < camera.width_px; ++col) {
      const cv::Point2f& r = rays[static_cast<std::size_t>(row * camera.width_px + col)];
      map_x_.at<float>(row, col) = static_cast<float>(cx + f * r.x);
      map_y_.at<float>(row, col) = static_cast<float>(cy + f * r.y);
    }
  }
}

cv::Mat DistortedCamera::render(const sim_camera::World& world, const CameraPose& pose) {
  sim_camera::View view;
  view.position_m = pose.eye_m.head<2>();
  view.yaw_rad = pose.yaw_rad;
  view.camera = render_spec_;
  view.camera.height_m = pose.eye_m.z();
  view.camera.pitch_rad = pose.pitch_rad;
  renderer_.render(world, view, rendered_);
  cv::Mat smooth;
  cv::GaussianBlur(rendered_.image, smooth, cv::Size(0, 0), 0.5 * kSupersample);
  cv::Mat image;
  cv::remap(smooth, image, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return image;
}

}  // namespace flowsteer::calibration::test
