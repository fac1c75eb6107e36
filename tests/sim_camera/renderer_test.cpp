#include "flowsteer/sim_camera/renderer.hpp"

#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/sim_camera/sim_camera.hpp"

namespace flowsteer::sim_camera {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Renderer& renderer() {
  static std::unique_ptr<Renderer> r = Renderer::create();
  return *r;
}

AgentSpec observer(Eigen::Vector2d start, double heading_rad, double speed) {
  AgentSpec a;
  a.start_m = start;
  a.heading_rad = heading_rad;
  a.start_speed_mps = speed;
  a.goals = {start + 20.0 * Eigen::Vector2d(std::cos(heading_rad), std::sin(heading_rad))};
  a.camera.width_px = 160;
  a.camera.height_px = 120;
  a.camera.hfov_rad = 90.0 * kDeg;
  a.camera.height_m = 1.5;
  return a;
}

Solid box(Eigen::Vector2d centre, Eigen::Vector2d size, double height) {
  Solid s;
  s.centre_m = centre;
  s.size_m = size;
  s.height_m = height;
  return s;
}

TEST(Renderer, DescribesItsContext) {
  EXPECT_NE(renderer().description().find("OpenGL"), std::string::npos);
}

TEST(Renderer, DepthOfABoxFaceAndIdsFollowTheGeometry) {
  WorldSpec spec;
  spec.agents = {observer({0.0, 0.0}, 0.0, 1.0)};
  spec.obstacles = {box({5.0, 0.0}, {1.0, 2.0}, 3.0)};  // front face at x = 4.5
  World world(spec);
  RenderedView out;
  renderer().render(world, View::of_agent(world, 0), out);
  ASSERT_EQ(out.depth_m.cols, 160);
  ASSERT_EQ(out.depth_m.rows, 120);
  const int centre_col = 80;
  const int centre_row = 60;
  EXPECT_EQ(out.object_ids.at<std::int32_t>(centre_row, centre_col), obstacle_render_id(0));
  EXPECT_NEAR(out.depth_m.at<float>(centre_row, centre_col), 4.5, 0.045);
  // Top rows: sky; bottom rows: ground; the box spans |x| < 1 / 4.5 in normalised units.
  EXPECT_EQ(out.object_ids.at<std::int32_t>(0, 5), servo::kSkyId);
  EXPECT_EQ(out.object_ids.at<std::int32_t>(119, 5), servo::kGroundId);
  EXPECT_TRUE(std::isinf(out.depth_m.at<float>(0, 5)));
  const base::CameraIntrinsics k = View::of_agent(world, 0).intrinsics();
  for (int col = 0; col < 160; ++col) {
    const double x = (col - k.cx_px) / k.fx_px;
    if (std::abs(std::abs(x) - 1.0 / 4.5) < 0.02) {
      continue;  // the edge itself
    }
    const bool on_box = std::abs(x) < 1.0 / 4.5;
    EXPECT_EQ(out.object_ids.at<std::int32_t>(centre_row, col) == obstacle_render_id(0), on_box)
        << "col " << col;
  }
  // The ground's depth at the bottom row: Z = h / y.
  const double y_bottom = (119 - k.cy_px) / k.fy_px;
  EXPECT_NEAR(out.depth_m.at<float>(119, 5), 1.5 / y_bottom, 0.01 * 1.5 / y_bottom);
}

Solid cylinder(Eigen::Vector2d centre, double radius, double height) {
  Solid s;
  s.shape = Solid::Shape::cylinder;
  s.centre_m = centre;
  s.radius_m = radius;
  s.height_m = height;
  return s;
}

// The analytic ray-caster's scene (servo/analytic_scene.hpp) seen from `view`, with no objects.
servo::AnalyticScene analytic_scene(const View& view) {
  servo::AnalyticScene scene;
  scene.intrinsics = view.intrinsics();
  scene.mount = {view.camera.height_m, view.camera.pitch_rad};
  scene.agent_speed_mps = view.speed_mps;
  scene.agent_turn_rate = view.turn_rate;
  return scene;
}

// A world's cylinder as the ray-caster has it: in the axes of the body seen from.
servo::SceneObject analytic_cylinder(const View& view, const Solid& s, std::int32_t id,
                                     const Eigen::Vector2d& velocity_mps) {
  const Eigen::Rotation2D<double> to_body(-view.yaw_rad);
  servo::SceneObject o;
  o.shape = servo::SceneObject::Shape::cylinder;
  o.id = id;
  o.position_m = to_body * (s.centre_m - view.position_m);
  o.radius_m = s.radius_m;
  o.height_m = s.height_m;
  o.velocity_mps = to_body * velocity_mps;
  return o;
}

// The renderer's flow against the analytic ray-caster of the servo core on the same scene:
// a post, a moving cylinder, the ground and the sky, seen by a turning, pitched camera.
TEST(Renderer, SyntheticFlowEqualsTheAnalyticFlow) {
  WorldSpec spec;
  AgentSpec me = observer({1.0, 2.0}, 30.0 * kDeg, 1.2);
  me.camera.pitch_rad = 5.0 * kDeg;
  spec.agents = {me};
  spec.obstacles = {cylinder({6.0, 4.5}, 0.5, 2.0)};
  MovingObstacle walker;
  walker.body = cylinder({0.0, 0.0}, 0.4, 1.7);
  walker.waypoints = {{7.0, 8.0}, {7.0, -4.0}};
  walker.speed_mps = 1.5;
  spec.moving = {walker};
  World world(spec);
  world.step({{0.0, 0.3}});  // turning right at 0.3 rad/s
  const View view = View::of_agent(world, 0);
  RenderedView out;
  renderer().render(world, view, out);

  servo::AnalyticScene scene = analytic_scene(view);
  scene.objects = {
      analytic_cylinder(view, spec.obstacles[0], obstacle_render_id(0), Eigen::Vector2d::Zero()),
      analytic_cylinder(view, world.moving_now(0), moving_render_id(0),
                        world.moving()[0].velocity_mps)};
  const servo::SceneRender truth = servo::render_scene(scene);

  std::map<std::int32_t, int> compared;
  double worst = 0.0;
  for (int row = 0; row < out.flow.rows; ++row) {
    for (int col = 0; col < out.flow.cols; ++col) {
      const std::int32_t id = out.object_ids.at<std::int32_t>(row, col);
      const std::size_t i = truth.flow.index(col, row);
      if (id != truth.ids[i]) {
        continue;  // a pixel on an edge, where the two rasterise differently
      }
      const cv::Vec2f f = out.flow.at<cv::Vec2f>(row, col);
      const Eigen::Vector2f& g = truth.flow.flow()[i];
      worst = std::max(worst, static_cast<double>((Eigen::Vector2f(f[0], f[1]) - g).norm()));
      ++compared[id];
    }
  }
  EXPECT_GT(compared[obstacle_render_id(0)], 100);
  EXPECT_GT(compared[moving_render_id(0)], 100);
  EXPECT_GT(compared[servo::kGroundId], 1000);
  EXPECT_GT(compared[servo::kSkyId], 1000);
  EXPECT_LT(worst, 1e-3);
}

TEST(Renderer, ShadowedGroundIsDarkerByTheAmbientRatio) {
  WorldSpec spec;
  spec.ground.pattern = Material::Pattern::plain;
  spec.lighting.ambient = 0.25F;
  spec.lighting.sun = SunLight{0.0, 45.0 * kDeg, 0.6F, true};  // from +x, 45° up
  AgentSpec me = observer({0.0, 0.0}, 0.0, 1.0);
  me.camera.pitch_rad = 30.0 * kDeg;
  spec.agents = {me};
  // A wall across the view, lit from behind: its shadow falls towards the agent.
  spec.obstacles = {box({9.0, 0.0}, {0.2, 30.0}, 4.0)};
  World world(spec);
  RenderedView out;
  renderer().render(world, View::of_agent(world, 0), out);
  // The shadow reaches 4 m in front of the wall (45°): ground from x = 5 to 8.9 is in shadow.
  const base::CameraIntrinsics k = View::of_agent(world, 0).intrinsics();
  auto ground_row = [&](double distance) {
    // Row whose ray meets the ground at `distance` ahead, for a camera pitched down by 30°.
    const double angle = std::atan2(1.5, distance) - 30.0 * kDeg;
    return static_cast<int>(std::lround(k.cy_px + k.fy_px * std::tan(angle)));
  };
  const int lit_row = ground_row(3.0);
  const int shadow_row = ground_row(7.0);
  ASSERT_EQ(out.object_ids.at<std::int32_t>(lit_row, 80), servo::kGroundId);
  ASSERT_EQ(out.object_ids.at<std::int32_t>(shadow_row, 80), servo::kGroundId);
  auto luminance = [&](int row) {
    const cv::Vec3b bgr = out.image.at<cv::Vec3b>(row, 80);
    return std::pow((bgr[0] + bgr[1] + bgr[2]) / (3.0 * 255.0), 2.2);  // back to linear
  };
  // Lit: ambient + sun·sin(45°); shadowed: ambient alone.
  const double expected = 0.25 / (0.25 + 0.6 * std::sin(45.0 * kDeg));
  EXPECT_NEAR(luminance(shadow_row) / luminance(lit_row), expected, 0.03);
}

// A box's faces seen from every side and from above: each is drawn, at the depth of the face
// nearest the camera (the faces are wound so that face culling keeps those seen from outside).
TEST(Renderer, EveryFaceOfABoxIsSeenFromOutside) {
  WorldSpec spec;
  spec.obstacles = {box({0.0, 0.0}, {1.0, 2.0}, 1.0)};
  struct Side {
    Eigen::Vector2d eye;
    double eye_height_m;
    double pitch_rad;  // down, so that the view's centre meets the face's
    double face_depth_m;
  };
  const Side sides[] = {{{4.0, 0.0}, 0.5, 0.0, 3.5},
                        {{-4.0, 0.0}, 0.5, 0.0, 3.5},
                        {{0.0, 5.0}, 0.5, 0.0, 4.0},
                        {{0.0, -5.0}, 0.5, 0.0, 4.0},
                        // the top face's centre, 1 m high, from 1.5 m beside it and 4 m above
                        {{1.5, 0.0}, 5.0, std::atan2(4.0, 1.5), std::hypot(4.0, 1.5)}};
  for (const Side& side : sides) {
    AgentSpec me = observer(side.eye, std::atan2(-side.eye.y(), -side.eye.x()), 0.0);
    me.camera.height_m = side.eye_height_m;
    me.camera.pitch_rad = side.pitch_rad;
    spec.agents = {me};
    World world(spec);
    const View view = View::of_agent(world, 0);
    const base::CameraIntrinsics k = view.intrinsics();
    RenderedView out;
    renderer().render(world, view, out);
    SCOPED_TRACE("eye at " + std::to_string(side.eye.x()) + ", " + std::to_string(side.eye.y()));
    // The principal point lies between the four centre pixels; their depths are within a
    // pixel's reach of the centre's.
    const int row = static_cast<int>(k.cy_px);
    const int col = static_cast<int>(k.cx_px);
    EXPECT_EQ(out.object_ids.at<std::int32_t>(row, col), obstacle_render_id(0));
    EXPECT_NEAR(out.depth_m.at<float>(row, col), side.face_depth_m, 0.02);
  }
}

// Cylinders at 2 to 60 m, each drawn at the level of detail its distance allows, against the
// analytic ray-caster's exact circles: the pixels whose object differs lie on the outline, and
// are at most a third of it (a quarter-pixel band each side of it, and fewer); with the
// coarsest level everywhere, the three nearest would differ on more than their outline.
TEST(Renderer, CylindersAtEveryLevelOfDetailKeepTheirOutline) {
  WorldSpec spec;
  AgentSpec me = observer({0.0, 0.0}, 0.0, 0.0);
  me.camera.width_px = 640;
  me.camera.height_px = 480;
  spec.agents = {me};
  const double distances_m[] = {2.0, 5.0, 12.0, 30.0, 60.0};
  for (std::size_t k = 0; k < std::size(distances_m); ++k) {
    const double bearing = (-30.0 + 15.0 * static_cast<double>(k)) * kDeg;
    spec.obstacles.push_back(
        cylinder(distances_m[k] * Eigen::Vector2d(std::cos(bearing), std::sin(bearing)), 0.3, 1.7));
  }
  World world(spec);
  const View view = View::of_agent(world, 0);
  RenderedView out;
  renderer().render(world, view, out);

  servo::AnalyticScene scene = analytic_scene(view);
  for (std::size_t k = 0; k < spec.obstacles.size(); ++k) {
    scene.objects.push_back(
        analytic_cylinder(view, spec.obstacles[k], obstacle_render_id(k), Eigen::Vector2d::Zero()));
  }
  const servo::SceneRender truth = servo::render_scene(scene);
  auto truth_id = [&](int col, int row) { return truth.ids[truth.flow.index(col, row)]; };
  std::map<std::int32_t, int> outline;
  std::map<std::int32_t, int> differing;
  for (int row = 1; row + 1 < out.object_ids.rows; ++row) {
    for (int col = 1; col + 1 < out.object_ids.cols; ++col) {
      const std::int32_t id = truth_id(col, row);
      const std::int32_t drawn = out.object_ids.at<std::int32_t>(row, col);
      if (id < 0 && drawn < 0) {
        continue;  // the ground meets the sky nearer in the renderer than in the ray-caster
      }
      const bool on_outline = id != truth_id(col - 1, row) || id != truth_id(col + 1, row) ||
                              id != truth_id(col, row - 1) || id != truth_id(col, row + 1);
      outline[id] += on_outline ? 1 : 0;
      if (drawn != id) {
        EXPECT_TRUE(on_outline) << "row " << row << " col " << col;
        ++differing[id];
      }
    }
  }
  for (std::size_t k = 0; k < spec.obstacles.size(); ++k) {
    const std::int32_t id = obstacle_render_id(k);
    SCOPED_TRACE("cylinder at " + std::to_string(distances_m[k]) + " m");
    EXPECT_GT(outline[id], 10);
    EXPECT_LE(differing[id], outline[id] / 3);
  }
}

bool same_bits(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

// Agents on a circle, each looking across it past a wall, with posts from 10 to 120 m away (so
// that the views draw cylinders at every level of detail, and leave out those between pixel
// centres). The first two cameras are so large that a submission holds one of their views only,
// the third's is smaller than the others', and the 20 others are more than a submission draws:
// five submissions of views of one size.
TEST(Renderer, ViewsRenderedTogetherAreTheViewsRenderedOneByOne) {
  WorldSpec spec;
  spec.lighting.sun = SunLight{0.5, 40.0 * kDeg, 0.6F, true};
  constexpr int kAgents = 23;
  for (int k = 0; k < kAgents; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / kAgents;
    const Eigen::Vector2d start = 6.0 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    spec.agents.push_back(observer(start, angle + std::numbers::pi + 0.2, 1.0 + 0.02 * k));
  }
  for (const std::size_t i : {0, 1}) {
    spec.agents[i].camera.width_px = 2048;
    spec.agents[i].camera.height_px = 1024;
  }
  spec.agents[2].camera.width_px = 96;
  spec.agents[2].camera.height_px = 64;
  spec.obstacles = {box({0.0, 2.0}, {3.0, 0.3}, 2.0)};
  for (int k = 1; k <= 12; ++k) {
    const double angle = 0.5 * k;
    spec.obstacles.push_back(
        cylinder(10.0 * k * Eigen::Vector2d(std::cos(angle), std::sin(angle)), 0.3, 1.7));
  }
  World world(spec);
  std::vector<View> views;
  for (std::size_t i = 0; i < spec.agents.size(); ++i) {
    View view = View::of_agent(world, i);
    view.turn_rate = 0.01 * static_cast<double>(i) - 0.1;
    views.push_back(view);
  }
  std::vector<RenderedView> alone(views.size());
  for (std::size_t i = 0; i < views.size(); ++i) {
    renderer().render(world, views[i], alone[i], RenderChannels::all);
  }
  for (const ViewSubmission submission : {ViewSubmission::layered, ViewSubmission::per_view}) {
    SCOPED_TRACE(submission == ViewSubmission::layered ? "layered" : "per view");
    const std::unique_ptr<Renderer> batch_renderer = Renderer::create(submission);
    std::vector<RenderedView> together(views.size());
    std::vector<RenderedView*> targets;
    for (RenderedView& out : together) {
      targets.push_back(&out);
    }
    batch_renderer->render_geometry(world, views, targets);
    int walls_seen = 0;
    for (std::size_t i = 0; i < views.size(); ++i) {
      SCOPED_TRACE("view " + std::to_string(i));
      EXPECT_TRUE(together[i].image.empty());
      EXPECT_TRUE(same_bits(together[i].object_ids, alone[i].object_ids));
      EXPECT_TRUE(same_bits(together[i].flow, alone[i].flow));
      EXPECT_TRUE(same_bits(together[i].depth_m, alone[i].depth_m));
      // What the views show: other agents, never the viewer itself.
      const std::set<std::int32_t> seen(together[i].object_ids.begin<std::int32_t>(),
                                        together[i].object_ids.end<std::int32_t>());
      EXPECT_FALSE(seen.contains(agent_render_id(i)));
      int others_seen = 0;
      for (std::size_t j = 0; j < views.size(); ++j) {
        others_seen += j != i && seen.contains(agent_render_id(j)) ? 1 : 0;
      }
      EXPECT_GT(others_seen, 0);
      walls_seen += seen.contains(obstacle_render_id(0)) ? 1 : 0;
    }
    EXPECT_GE(walls_seen, 2);
    const std::vector<RenderedView*> too_few(targets.begin(), targets.end() - 1);
    EXPECT_THROW(batch_renderer->render_geometry(world, views, too_few), std::invalid_argument);
  }
}

// An agent that has left the world (Arrival::leave) is drawn by neither path, and a geometry
// batch built while it was there draws the others as before.
TEST(Renderer, AnAgentThatLeftIsNotDrawn) {
  WorldSpec spec;
  spec.arrival = Arrival::leave;
  spec.agents = {observer({0.0, 0.0}, 0.0, 0.0), observer({3.0, 0.0}, 0.0, 0.0)};
  spec.agents[1].goals = {spec.agents[1].start_m};  // at its goal: it leaves at the first step
  spec.obstacles = {box({6.0, 0.0}, {0.3, 4.0}, 2.0)};
  World world(spec);
  const std::unique_ptr<Renderer> batch_renderer = Renderer::create();
  auto seen = [&] {
    RenderedView lit;
    renderer().render(world, View::of_agent(world, 0), lit, RenderChannels::all);
    RenderedView geometry;
    RenderedView* target = &geometry;
    const View view = View::of_agent(world, 0);
    batch_renderer->render_geometry(world, std::span(&view, 1), std::span(&target, 1));
    EXPECT_TRUE(same_bits(lit.object_ids, geometry.object_ids));
    return std::set<std::int32_t>(lit.object_ids.begin<std::int32_t>(),
                                  lit.object_ids.end<std::int32_t>());
  };
  const std::set<std::int32_t> before = seen();
  EXPECT_TRUE(before.contains(agent_render_id(1)));
  world.step({{0.0, 0.0}, {0.0, 0.0}});
  ASSERT_FALSE(world.present(1));
  const std::set<std::int32_t> after = seen();
  EXPECT_FALSE(after.contains(agent_render_id(1)));
  EXPECT_TRUE(after.contains(obstacle_render_id(0)));
}

TEST(SimCamera, DeliversFramesWithSimulatorChannels) {
  WorldSpec spec;
  spec.agents = {observer({0.0, 0.0}, 0.0, 1.0)};
  World world(spec);
  SimCamera camera(world, renderer(), 0);
  camera_io::Frame frame;
  ASSERT_EQ(camera.read(frame, 0.1), camera_io::ReadStatus::ok);
  ASSERT_EQ(camera.read(frame, 0.1), camera_io::ReadStatus::ok);
  EXPECT_EQ(frame.sequence, 1U);
  EXPECT_EQ(frame.image.type(), CV_8UC3);
  ASSERT_TRUE(frame.sim.has_value());
  EXPECT_EQ(frame.sim->flow.type(), CV_32FC2);
  EXPECT_EQ(camera.intrinsics().width_px, 160);
}

}  // namespace
}  // namespace flowsteer::sim_camera
