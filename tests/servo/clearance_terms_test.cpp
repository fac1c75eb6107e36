// The flowsteer law's terms (clearance_terms.cpp): each gradient against finite differences of
// its cost along the two-body simulation, and the behaviour each term is there for.
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/servo/control.hpp"
#include "two_body.hpp"

namespace flowsteer::servo {
namespace {

constexpr double kLn10 = 2.302585092994046;

// The features of a point object of the two-body simulation: extent one point, depth exact.
ObjectFeatures point_object(const test::TwoBody& s, std::int32_t id = 1) {
  ObjectFeatures o;
  o.source_id = id;
  o.pixel_count = 100;
  o.centre = {s.image_x(), 0.0};
  o.min_x = o.max_x = s.image_x();
  o.width = 0.0;
  o.depth_m = o.min_x_depth_m = o.max_x_depth_m = s.depth();
  o.status = MotionStatus::approaching;
  o.foe = {s.foe_x(), 0.0};
  o.ttc_s = s.ttc();
  return o;
}

// The law for an agent agent_width_m wide without a margin that prefers no side to pass on.
FlowsteerOptions law_without_convention(double agent_width_m) {
  FlowsteerOptions options = flowsteer_options({.agent_width_m = agent_width_m});
  options.clearance.passing_side = PassingSide::none;
  return options;
}
ClearanceOptions options_without_convention(double agent_width_m) {
  return law_without_convention(agent_width_m).clearance;
}

// ∂L̇/∂ω and ∂L̇/∂a_c of `cost` along the simulation, by finite differences.
template <typename Cost>
TermGradient simulated(const test::TwoBody& s, Cost cost) {
  const double base = test::rate_of(s, 0.0, 0.0, cost);
  return {cost(s), (test::rate_of(s, 0.8, 0.0, cost) - base) / 0.8,
          (test::rate_of(s, 0.0, 0.5, cost) - base) / 0.5};
}

void expect_gradient(const TermGradient& g, const TermGradient& expected) {
  EXPECT_NEAR(g.cost, expected.cost, 1e-9 * (1.0 + std::abs(expected.cost)));
  EXPECT_NEAR(g.per_accel, expected.per_accel, 1e-4 * (1.0 + std::abs(expected.per_accel)));
  EXPECT_NEAR(g.per_turn, expected.per_turn, 1e-4 * (1.0 + std::abs(expected.per_turn)));
}

// L_c = I(τ) φ(c/σ), c the FOE's clearance from the object's end widened by half the agent's
// width (a point of the object that far to the side, moving with it), I and σ held constant.
// I is that of the time to contact, τ (1 − w / 2Z). The curvatures are Gauss–Newton's, I φ''
// (ġap per control / σ)², with the gap's rates by finite differences.
void check_clearance(const test::TwoBody& s, double agent_width_m, int end) {
  const double half = 0.5 * agent_width_m * (end == 0 ? -1.0 : 1.0);
  const Eigen::Vector2d offset = half * s.right();  // fixed in the world: a point of the object
  const double sigma = agent_width_m / s.depth() / kLn10;
  const double importance = -2.0 * s.ttc() * (1.0 - 0.5 * agent_width_m / s.depth()) + 10.0;
  auto gap = [&](const test::TwoBody& b) {
    test::TwoBody edge = b;
    edge.point += offset;
    return end == 0 ? edge.image_x() - b.foe_x() : b.foe_x() - edge.image_x();
  };
  auto cost = [&](const test::TwoBody& b) {
    const double u = gap(b) / sigma;
    return importance * (u >= 0.0 ? std::exp(-u) : 1.0 - u);
  };
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  const TermGradient g = clearance_term(options_without_convention(agent_width_m))
                             ->evaluate({objects, {}, {}, {}}, {s.agent_speed});
  expect_gradient(g, simulated(s, cost));
  EXPECT_NE(g.per_turn, 0.0);

  const TermGradient gap_rate = simulated(s, gap);
  const double u = gap(s) / sigma;
  const double phi_curvature = u >= 0.0 ? std::exp(-u) : 0.0;
  const double c = importance * phi_curvature / (sigma * sigma);
  EXPECT_NEAR(g.curvature_turn, c * gap_rate.per_turn * gap_rate.per_turn,
              1e-4 * (1.0 + g.curvature_turn));
  EXPECT_NEAR(g.curvature_accel, c * gap_rate.per_accel * gap_rate.per_accel,
              1e-4 * (1.0 + g.curvature_accel));
}

TEST(ClearanceGradient, OutsideTheWidenedExtentMatchesSimulation) {
  test::TwoBody s;  // a point 6 m ahead, 2 m to the right, crossing to the left
  s.point = {6.0, -2.0};
  s.point_velocity = {-0.3, 0.35};
  s.agent_speed = 1.2;
  check_clearance(s, 0.8, 0);  // the FOE is left of it: passed by its left end
}

TEST(ClearanceGradient, InsideTheWidenedExtentMatchesSimulation) {
  test::TwoBody s;  // nearly on course, just left: passed by its right end
  s.point = {5.0, 0.15};
  s.point_velocity = {-0.5, 0.0};
  s.agent_speed = 1.0;
  check_clearance(s, 1.0, 1);
}

TEST(ClearanceBehaviour, AStaticObstacleJustRightOfTheHeadingTurnsLeft) {
  test::TwoBody s;
  s.point = {4.0, -0.3};
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  Controller c(flowsteer_goal_reaching({}, law_without_convention(1.0)), 1.0, {10.0, 10.0});
  EXPECT_LT(c.step({objects, 0.0, 10.0, {}}, {1.0}).command.turn_rate, 0.0);
}

TEST(ClearanceBehaviour, KeepingRightTurnsRightForAPersonMetHeadOn) {
  test::TwoBody s;  // exactly on course, coming straight at the agent
  s.point = {6.0, 0.0};
  s.point_velocity = {-1.0, 0.0};
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  const FlowsteerOptions keep_right = flowsteer_options({.agent_width_m = 1.0});
  Controller right(flowsteer_goal_reaching({}, keep_right), 1.0, {10.0, 10.0});
  EXPECT_GT(right.step({objects, 0.0, 20.0, {}}, {1.0}).command.turn_rate, 0.0);
  FlowsteerOptions keep_left = keep_right;
  keep_left.clearance.passing_side = PassingSide::keep_left;
  Controller left(flowsteer_goal_reaching({}, keep_left), 1.0, {10.0, 10.0});
  EXPECT_LT(left.step({objects, 0.0, 20.0, {}}, {1.0}).command.turn_rate, 0.0);
}

// Two static posts 0.6 m apart 4 m ahead: their widened extents overlap, so the agent goes
// round both, not through the gap between them, which the FOE (straight ahead) is in.
TEST(ClearanceBehaviour, TwoObjectsTooCloseToPassBetweenArePassedOnTheOutside) {
  test::TwoBody left_post;
  left_post.point = {4.0, 0.3};
  test::TwoBody right_post;
  right_post.point = {4.0, -0.3};
  std::vector<ObjectFeatures> objects = {point_object(left_post, 1), point_object(right_post, 2)};
  objects[0].min_x -= 0.02;  // the left post a little wider: the right way round is shorter
  TermGradient g =
      clearance_term(options_without_convention(1.0))->evaluate({objects, {}, {}, {}}, {1.0});
  // Each post alone would push the FOE away from itself, to opposite sides, and the pushes
  // would cancel; together, both push it right.
  EXPECT_LT(g.per_turn, 0.0);  // ω = −∂L̇/∂ω > 0: turn right
}

// A post 4 m ahead on course, the goal 2 m ahead: the agent stops at the goal short of the post,
// which is left out; with the goal past the post, the post is in the way.
TEST(ClearanceBehaviour, AnObjectBeyondTheGoalIsLeftOut) {
  test::TwoBody s;
  s.point = {4.0, 0.05};
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  const auto term = clearance_term(options_without_convention(1.0));
  const TermGradient before_goal = term->evaluate({objects, 0.0, 2.0, {}}, {1.0});
  EXPECT_EQ(before_goal.cost, 0.0);
  EXPECT_EQ(before_goal.per_turn, 0.0);
  EXPECT_GT(term->evaluate({objects, 0.0, 6.0, {}}, {1.0}).cost, 1.0);
}

// A person 2.4 m away, 60° to the left, beside a goal 1.35 m away that the agent is turning
// towards: its depth (1.2 m) is less than the goal's distance, but no point of the straight path
// to the goal comes within half the kept width of it. With the goal further, it counts.
TEST(ClearanceBehaviour, AnObjectFurtherThanTheGoalSeenAtAnAngleIsLeftOut) {
  test::TwoBody s;
  s.point = {1.2, 2.4 * std::sin(std::numbers::pi / 3.0)};
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  const auto term = clearance_term(options_without_convention(0.8));
  EXPECT_EQ(term->evaluate({objects, -1.4, 1.35, {}}, {1.0}).cost, 0.0);
  EXPECT_GT(term->evaluate({objects, -1.4, 3.0, {}}, {1.0}).cost, 0.0);
}

// The margin is kept in proportion to the speed: stepping slowly, the agent needs only its own
// width, and the same post beside its course costs less.
TEST(ClearanceBehaviour, ASlowAgentKeepsLessRoom) {
  test::TwoBody s;
  s.point = {3.0, -0.7};
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  ClearanceOptions options = options_without_convention(0.6);
  options.threats.kept_width.margin_m = 0.5;
  options.threats.kept_width.margin_full_speed_mps = 1.0;
  const auto term = clearance_term(options);
  const double walking = term->evaluate({objects, {}, {}, {}}, {1.0}).cost;
  const double stepping = term->evaluate({objects, {}, {}, {}}, {0.2}).cost;
  EXPECT_LT(stepping, 0.5 * walking);
  EXPECT_EQ(term->evaluate({objects, {}, {}, {}}, {2.0}).cost, walking);  // full from 1 m/s
}

// A static wall along the path `right_m` to the right, from 1 m to 10 m ahead, seen by an agent
// walking at 1 m/s.
ObjectFeatures wall_along_the_path(double right_m) {
  ObjectFeatures wall;
  wall.source_id = 4;
  wall.pixel_count = 1000;
  wall.min_x = right_m / 10.0;
  wall.max_x = right_m / 1.0;
  wall.centre = {0.5 * (wall.min_x + wall.max_x), 0.0};
  wall.min_x_depth_m = 10.0;
  wall.max_x_depth_m = 1.0;
  wall.depth_m = 3.0;
  wall.status = MotionStatus::approaching;
  wall.foe = {0.0, 0.0};
  wall.ttc_s = 3.0;
  wall.fit.static_foe = true;
  return wall;
}

// A wall along the path 1.5 m to the right: the straight course passes it by more than half the
// kept width (0.5 m) and static_clearance_m (0.25 m). Static, it is left out; were it moving it
// could turn into the path, and its cost's tail would still push.
TEST(ClearanceBehaviour, AStaticObjectTheCoursePassesClearOfIsLeftOut) {
  ObjectFeatures wall = wall_along_the_path(1.5);
  const ClearanceOptions options = options_without_convention(1.0);
  auto cost = [&](const ObjectFeatures& object) {
    const std::vector<ObjectFeatures> objects = {object};
    return clearance_term(options)->evaluate({objects, {}, {}, {}}, {1.0}).cost;
  };
  EXPECT_EQ(cost(wall), 0.0);
  wall.fit.static_foe = false;
  EXPECT_GT(cost(wall), 0.0);
  EXPECT_GT(cost(wall_along_the_path(0.7)), 0.0);  // within the margin
}

// A person standing 4 m ahead, 0.1 m left of the course, with a wall along the path 0.9 m to the
// right. Alone, the person is passed on its right, the nearer way round. The wall is passed clear
// and costs nothing of its own, but leaves no room between it and the person: the two are one
// group, and the person is passed on its left.
TEST(ClearanceBehaviour, AWallPassedClearClosesTheGapBesideAPersonAhead) {
  test::TwoBody person_at;
  person_at.point = {4.0, 0.1};
  ObjectFeatures person = point_object(person_at, 1);
  person.fit.static_foe = true;
  const ObjectFeatures wall = wall_along_the_path(0.9);
  // A term of its own for each: the side taken is remembered from step to step.
  const auto gradient = [](const std::vector<ObjectFeatures>& objects) {
    return clearance_term(options_without_convention(1.0))->evaluate({objects, {}, {}, {}}, {1.0});
  };
  EXPECT_EQ(gradient({wall}).cost, 0.0);
  EXPECT_LT(gradient({person}).per_turn, 0.0);        // ω = −∂L̇/∂ω > 0: turn right
  EXPECT_GT(gradient({person, wall}).per_turn, 0.0);  // turn left
}

// A car 1.8 m wide and 4.2 m long crossing from the left at 2.5 m/s on a collision course with
// an agent walking at 1 m/s (CGF's street): its near side 4.1 m ahead, its front corner 12.5 m to
// the left, so that both reach the point 5 m ahead after 5 s. Seen by the agent 72° to the left,
// the FOE lies nearer its front end than its rear in the image, and the clearance term, left to
// the image gaps, passes in front: it speeds the agent up. A car is passed behind: the term brakes.
ObjectFeatures crossing_car(double near_side_m, double agent_speed_mps) {
  test::TwoBody front;  // x forward, y left: the car moves to the agent's right
  front.agent_speed = agent_speed_mps;
  front.point = {near_side_m, 2.5 * (near_side_m + 0.9)};
  front.point_velocity = {0.0, -2.5};
  test::TwoBody rear = front;
  rear.point.y() += 4.2;
  ObjectFeatures car = point_object(front, 3);
  car.min_x = rear.image_x();
  car.min_x_depth_m = rear.depth();
  car.centre = {0.5 * (car.min_x + car.max_x), 0.0};
  car.width = car.max_x - car.min_x;
  return car;
}

TEST(ClearanceBehaviour, ACarCrossingThePathIsPassedBehind) {
  const std::vector<ObjectFeatures> objects = {crossing_car(4.1, 1.0)};
  ClearanceOptions options = options_without_convention(0.6);
  const TermGradient yielding = clearance_term(options)->evaluate({objects, {}, {}, {}}, {1.0});
  options.yield_speed_ratio = std::numeric_limits<double>::infinity();
  const TermGradient by_the_gaps = clearance_term(options)->evaluate({objects, {}, {}, {}}, {1.0});
  EXPECT_GT(yielding.per_accel, 0.0);  // a_c = −λ ∂L̇/∂a_c < 0: it slows and lets the car pass
  EXPECT_LT(by_the_gaps.per_accel, 0.0);
}

// The same car with its near side 1.2 m ahead (its path 0.9 m ahead for the agent's disc), the
// agent at 1.5 m/s: it stops in 2.25 m at stop_decel_mps2, inside the car's path. Braking would
// leave it standing in the lane: it passes as it would anything else, here in front. At 0.5 m/s
// it stops in 0.25 m and gives way.
TEST(ClearanceBehaviour, ACarIsNotYieldedToWhereTheAgentCannotStopShortOfItsPath) {
  ClearanceOptions options = options_without_convention(0.6);
  const auto yielding = clearance_term(options);
  options.yield_speed_ratio = std::numeric_limits<double>::infinity();
  const auto by_the_gaps = clearance_term(options);
  const std::vector<ObjectFeatures> fast = {crossing_car(1.2, 1.5)};
  const TermGradient in_front = yielding->evaluate({fast, {}, {}, {}}, {1.5});
  EXPECT_LT(in_front.per_accel, 0.0);
  EXPECT_EQ(in_front.per_accel, by_the_gaps->evaluate({fast, {}, {}, {}}, {1.5}).per_accel);
  const std::vector<ObjectFeatures> slow = {crossing_car(1.2, 0.5)};
  EXPECT_GT(yielding->evaluate({slow, {}, {}, {}}, {0.5}).per_accel, 0.0);
  EXPECT_LT(by_the_gaps->evaluate({slow, {}, {}, {}}, {0.5}).per_accel, 0.0);
}

TEST(BrakingGradient, MatchesSimulation) {
  test::TwoBody s;  // a static obstacle 2 m ahead on course, the agent at 1.3 m/s
  s.point = {2.0, 0.0};
  s.agent_speed = 1.3;
  const BrakingOptions options = law_without_convention(1.0).braking;
  const double stopping_speed = std::sqrt(2.0 * options.stop_decel_mps2 * (2.0 - 0.5));
  auto cost = [&](const test::TwoBody& b) {
    const double excess = std::max(0.0, b.agent_speed - stopping_speed);
    return 0.5 * excess * excess;  // ψ = 1: the FOE is on it
  };
  const std::vector<ObjectFeatures> objects = {point_object(s)};
  const TermGradient g = braking_term(options)->evaluate({objects, {}, {}, {}}, {s.agent_speed});
  expect_gradient(g, simulated(s, cost));
  EXPECT_GT(g.per_accel, 0.0);  // a_c < 0: brakes
}

TEST(BrakingBehaviour, AWallMetHeadOnStopsTheAgentShortOfIt) {
  ObjectFeatures wall;
  wall.source_id = 3;
  wall.pixel_count = 1000;
  wall.centre = {0.0, 0.0};
  wall.min_x = -1.0;
  wall.max_x = 1.0;
  wall.width = 2.0;
  wall.cut_left = wall.cut_right = true;  // fills the view
  wall.depth_m = wall.min_x_depth_m = wall.max_x_depth_m = 1.5;
  wall.status = MotionStatus::approaching;
  wall.foe = {0.0, 0.0};
  wall.ttc_s = 1.5 / 1.3;
  const std::vector<ObjectFeatures> objects = {wall};
  FlowsteerWeights at_preferred_speed;
  at_preferred_speed.preferred_speed_mps = 1.3;
  at_preferred_speed.anticipation = 0.0;  // which brakes for the wall too, by its own measure
  Controller c(flowsteer_goal_reaching(at_preferred_speed, law_without_convention(1.0)), 1.0,
               {1.0, 1.0});
  // From 1.3 m/s it stops 1 m on at 0.5 m/s² only from 1 m/s: brake by ε (1.3 − 1.0).
  const ControlOutput out = c.step({objects, 0.0, 10.0, {}}, {1.3});
  EXPECT_NEAR(out.unclamped.accel_mps2, -2.0 * 0.3, 1e-9);
}

TEST(HeadingGradient, MatchesSimulation) {
  test::TwoBody s;
  s.point = {3.0, -2.5};  // a goal well to the right
  s.agent_speed = 0.8;
  const double distance = s.point.norm();
  auto cost = [](const test::TwoBody& b) { return 0.5 * std::pow(std::atan(b.image_x()), 2); };
  const TermGradient g =
      heading_term()->evaluate({{}, std::atan(s.image_x()), distance, {}}, {s.agent_speed});
  expect_gradient(g, simulated(s, cost));
}

// L_θ = ½ θ² with θ̇ = … − ω: its curvature along ω is 1, along a_c 0.
TEST(HeadingGradient, CurvatureIsOneAlongTheTurn) {
  test::TwoBody s;
  s.point = {3.0, -2.5};
  s.agent_speed = 0.8;
  auto bearing = [](const test::TwoBody& b) { return std::atan(b.image_x()); };
  const TermGradient rate = simulated(s, bearing);
  const TermGradient g =
      heading_term()->evaluate({{}, bearing(s), s.point.norm(), {}}, {s.agent_speed});
  EXPECT_NEAR(g.curvature_turn, rate.per_turn * rate.per_turn, 1e-5);
  EXPECT_NEAR(g.curvature_turn, 1.0, 1e-5);
  EXPECT_EQ(g.curvature_accel, 0.0);
}

TEST(HeadingBehaviour, TheTurnStaysBoundedForAGoalBesideOrBehind) {
  for (const double bearing : {1.5, 2.5, 3.1}) {
    const TermGradient g = heading_term()->evaluate({{}, bearing, 1.0, {}}, {1.0});
    EXPECT_NEAR(-g.per_turn, bearing, 1e-12);  // ω = λ α θ
  }
}

TEST(ApproachSpeedBehaviour, SlowsForAGoalInsideItsTurningCircle) {
  const auto term = approach_speed_term(1.3, 1.0);
  // 1 m away, 60° to the side: at a turn rate of 0.5 rad/s it reaches it at 0.29 m/s.
  const TermGradient near = term->evaluate({{}, std::numbers::pi / 3.0, 1.0, {}}, {1.3});
  const double target = 0.5 * 1.0 / (2.0 * std::sin(std::numbers::pi / 3.0));
  EXPECT_NEAR(near.per_accel, 1.3 - target, 1e-12);  // a_c = −β (v − v_t)
  // Straight ahead and far: the preferred speed.
  EXPECT_NEAR(term->evaluate({{}, 0.0, 4.0, {}}, {1.0}).per_accel, 1.0 - 1.3, 1e-12);
}

TEST(ApproachSpeedBehaviour, SlowsToStopAtTheGoal) {
  const auto term = approach_speed_term(1.3, 1.0, 0.5);
  // Straight ahead, 0.25 m away: the speed it stops from at 0.5 m/s² in 0.25 m, 0.5 m/s.
  EXPECT_NEAR(term->evaluate({{}, 0.0, 0.25, {}}, {1.3}).per_accel, 1.3 - 0.5, 1e-12);
}

// A still object as an agent standing still sees it: no flow, so no fit; its ends' depths only.
// Ends given on the ground in the agent's frame (x right, z forward).
ObjectFeatures standing_object(Eigen::Vector2d left, Eigen::Vector2d right) {
  ObjectFeatures o;
  o.source_id = 7;
  o.pixel_count = 500;
  o.min_x = left.x() / left.y();
  o.max_x = right.x() / right.y();
  o.centre = {0.5 * (o.min_x + o.max_x), 0.0};
  o.width = o.max_x - o.min_x;
  o.min_x_depth_m = left.y();
  o.max_x_depth_m = right.y();
  o.depth_m = 0.5 * (left.y() + right.y());
  return o;
}

// The agent 0.6 m wide with a margin of 0.5 m, of which 0.1 m kept at rest: it keeps 0.35 m
// from its centre while it stands.
FlowsteerOptions walker_law() {
  FlowsteerOptions options =
      flowsteer_options({.agent_width_m = 0.6, .margin_m = 0.5, .margin_full_speed_mps = 1.3});
  options.clearance.passing_side = PassingSide::none;
  return options;
}

// At rest and facing a wall 0.5 m ahead, it may only set off at the speed it stops from within
// the 0.15 m left: a target of 0 against the wall would hold it there.
TEST(ApproachSpeedBehaviour, SetsOffNoFasterThanItStopsShortOfAStandingWall) {
  const auto term = approach_speed_term(1.3, 1.0, 0.5, walker_law().approach_speed);
  ObjectFeatures wall = standing_object({-0.5, 0.5}, {0.5, 0.5});
  wall.cut_left = wall.cut_right = true;
  const std::vector<ObjectFeatures> objects = {wall};
  EXPECT_NEAR(term->evaluate({objects, 0.0, 10.0, {}}, {0.0}).per_accel, -std::sqrt(0.15), 1e-9);
  EXPECT_NEAR(term->evaluate({{}, 0.0, 10.0, {}}, {0.0}).per_accel, -1.3, 1e-12);
}

TEST(ApproachSpeedBehaviour, AStandingWallAlongTheCourseDoesNotSlowIt) {
  const auto term = approach_speed_term(1.3, 1.0, 0.5, walker_law().approach_speed);
  const std::vector<ObjectFeatures> objects = {standing_object({1.0, 10.0}, {1.0, 1.0})};
  EXPECT_NEAR(term->evaluate({objects, 0.0, 10.0, {}}, {0.0}).per_accel, -1.3, 1e-12);
}

// Heading 10° into a wall on its right that it stands 1 cm clear of: only the wall's part ahead is
// in view, cut by the image's right edge. The hidden part, taken to go on along the wall's line,
// is what its disc touches first, after 0.01 / sin 10° of walking.
TEST(ApproachSpeedBehaviour, AWallCutByTheImageGoesOnBesideTheAgent) {
  const double angle = 10.0 * std::numbers::pi / 180.0;
  const Eigen::Vector2d normal{std::cos(angle), std::sin(angle)};  // towards the wall
  const double distance = 0.35 + 0.01;
  auto on_wall = [&](double z) {
    return Eigen::Vector2d{(distance - z * normal.y()) / normal.x(), z};
  };
  ObjectFeatures wall = standing_object(on_wall(5.0), on_wall(1.0));
  const auto term = approach_speed_term(1.3, 1.0, 0.5, walker_law().approach_speed);
  auto target = [&](const ObjectFeatures& object) {
    const std::vector<ObjectFeatures> objects = {object};
    return -term->evaluate({objects, 0.0, 10.0, {}}, {0.0}).per_accel;
  };
  const double uncut = target(wall);
  wall.cut_right = true;
  EXPECT_NEAR(target(wall), std::sqrt(0.01 / std::sin(angle)), 1e-9);
  EXPECT_GT(uncut, 2.0 * target(wall));
}

// A building seen at its corner, 0.2 m right of the agent's course and 1.2 m ahead: one face runs
// from the corner along the course to 8 m, the other to the right. The line between the region's
// ends passes 0.2 m from the course only 8 m ahead; the corner, its nearest point, is what the
// agent's disc (0.35 m at rest) touches first.
TEST(ApproachSpeedBehaviour, ABuildingSeenAtItsCornerIsTouchedAtTheCorner) {
  ObjectFeatures building = standing_object({0.2, 8.0}, {3.0, 1.2});
  building.nearest_x = 0.2 / 1.2;
  building.nearest_depth_m = 1.2;
  const auto term = approach_speed_term(1.3, 1.0, 0.5, walker_law().approach_speed);
  auto target = [&](const ObjectFeatures& object) {
    const std::vector<ObjectFeatures> objects = {object};
    return -term->evaluate({objects, 0.0, 10.0, {}}, {0.0}).per_accel;
  };
  EXPECT_NEAR(target(building), std::sqrt(1.2 - std::sqrt(0.35 * 0.35 - 0.2 * 0.2)), 1e-9);
  building.nearest_depth_m.reset();
  EXPECT_NEAR(target(building), 1.3, 1e-12);
}

// Someone standing 0.5 m ahead, a little left of the agent's heading, both at rest: no flow, so
// nothing to avoid by the fit, and each would wait for the other. The agent takes them as it
// will see them once it walks, and turns to pass them on their right, the nearer way round.
TEST(ClearanceBehaviour, AnAgentAtRestTurnsToPassSomeoneStandingInItsWay) {
  const std::vector<ObjectFeatures> objects = {standing_object({-0.35, 0.5}, {0.15, 0.5})};
  const auto term = clearance_term(walker_law().clearance);
  const TermGradient at_rest = term->evaluate({objects, 0.0, 10.0, {}}, {0.0});
  EXPECT_GT(at_rest.cost, 0.0);
  Controller c(flowsteer_goal_reaching({}, walker_law()), 1.0, {1.0, 1.0});
  EXPECT_GT(c.step({objects, 0.0, 10.0, {}}, {0.0}).command.turn_rate, 0.0);
  // Walking, an object that shows no flow is not in the way. At rest, one further than half the
  // kept width and static_clearance_m is not either: nothing touches an agent that stands (the
  // approach speed holds it short of them, and the fit sees them once it walks).
  EXPECT_EQ(term->evaluate({objects, 0.0, 10.0, {}}, {0.5}).cost, 0.0);
  const std::vector<ObjectFeatures> metre = {standing_object({-0.35, 1.0}, {0.15, 1.0})};
  EXPECT_EQ(term->evaluate({metre, 0.0, 10.0, {}}, {0.0}).cost, 0.0);
}

// At rest with someone standing 0.5 m ahead, a little left: passed by their right end, nearer.
// Turning right brings a wall into view whose extent, widened, meets theirs: the pair is passed
// by its left end. Turning back takes the wall out of view, but the agent keeps the left end for
// rest_commit_s (it turned at ±max_turn_rate every other step, face to face with the other);
// after that, or with the hold off, the end follows what is in view.
TEST(ClearanceBehaviour, AnAgentAtRestKeepsTheEndItChoseWhenTurningTakesAWallOutOfView) {
  const ObjectFeatures person = standing_object({-0.45, 0.5}, {0.05, 0.5});
  ObjectFeatures wall = standing_object({0.25, 0.45}, {1.0, 0.3});
  wall.source_id = 8;
  const std::vector<ObjectFeatures> alone = {person};
  const std::vector<ObjectFeatures> with_wall = {person, wall};
  const AgentState at_rest{0.0, 0.05};
  auto turns = [&](CostTerm& term, const std::vector<ObjectFeatures>& objects) {
    return -term.evaluate({objects, 0.0, 10.0, {}}, at_rest).per_turn;  // ω's sign
  };
  ClearanceOptions options = walker_law().clearance;
  const auto term = clearance_term(options);
  EXPECT_GT(turns(*term, alone), 0.0);
  EXPECT_LT(turns(*term, with_wall), 0.0);
  int held_steps = 0;
  while (turns(*term, alone) < 0.0 && held_steps < 100) {
    ++held_steps;
  }
  EXPECT_NEAR(held_steps, 20, 1);  // 1 s of 0.05 s steps, counted down in floating point

  options.rest_commit_s = 0.0;
  const auto unheld = clearance_term(options);
  EXPECT_GT(turns(*unheld, alone), 0.0);
  EXPECT_LT(turns(*unheld, with_wall), 0.0);
  EXPECT_GT(turns(*unheld, alone), 0.0);
}

// Someone 3 m ahead, 0.9 to 1.3 m right of the course, whose FOE the fit finds where a static
// object's lies, straight ahead, as it does for anyone walking straight at the agent. Standing
// (τ = 3 s at 1 m/s) the course passes it clear; closing in at 2 m/s (τ = 1.5 s) it moves, may
// turn into the path, and costs. Without the check (static_closing switched off) the fit's word
// is taken.
TEST(ClearanceBehaviour, AnObjectClosingInFasterThanTheAgentWalksIsNotTakenAsStanding) {
  ObjectFeatures person = standing_object({0.9, 3.0}, {1.3, 3.0});
  person.nearest_x = person.min_x;
  person.nearest_depth_m = 3.0;
  person.status = MotionStatus::approaching;
  person.foe = {0.0, 0.0};
  person.fit.static_foe = true;
  ClearanceOptions options = options_without_convention(1.0);
  auto cost = [&](double ttc_s) {
    person.ttc_s = ttc_s;
    const std::vector<ObjectFeatures> objects = {person};
    return clearance_term(options)->evaluate({objects, {}, {}, {}}, {1.0}).cost;
  };
  EXPECT_EQ(cost(3.0), 0.0);
  EXPECT_GT(cost(1.5), 0.0);
  options.threats.static_closing_ratio = std::numeric_limits<double>::infinity();
  EXPECT_EQ(cost(1.5), 0.0);
}

// A wall on the right that the agent's heading meets 9.4 m ahead, its far end 8 m ahead and
// 0.235 m right of the course, its near end cut by the image beside the agent. Its fit, pulled
// towards the near pixels, gives τ = 0.8 s for a mean depth of 2.5 m. At 1 m/s the agent's disc
// (0.3 m and static_clearance_m) reaches the far end in 7.5 s, beyond the horizon: the wall is
// passed clear and costs nothing. Its velocity taken as Z/τ, 3.1 m/s, put that within 2.4 s. At
// 2 m/s it is 3.75 s away and in the way.
TEST(ClearanceBehaviour, AStaticWallIsApproachedAtTheAgentsOwnSpeed) {
  const double slope = std::tan(0.18);
  auto on_wall = [&](double z) { return Eigen::Vector2d{1.69 - z * slope, z}; };
  ObjectFeatures wall = standing_object(on_wall(8.0), on_wall(0.44));
  wall.cut_right = true;
  wall.status = MotionStatus::approaching;
  wall.foe = {0.0, 0.0};
  wall.ttc_s = 0.8;
  wall.depth_m = 2.5;
  wall.fit.static_foe = true;
  const std::vector<ObjectFeatures> objects = {wall};
  const auto term = clearance_term(options_without_convention(0.6));
  EXPECT_EQ(term->evaluate({objects, 0.0, 20.0, {}}, {1.0}).cost, 0.0);
  EXPECT_GT(term->evaluate({objects, 0.0, 20.0, {}}, {2.0}).cost, 0.0);
}

TEST(LeaderGapGradient, MatchesSimulation) {
  test::TwoBody s;
  s.point = {5.0, 0.7};
  s.point_velocity = {0.4, 0.3};
  s.agent_speed = 1.0;
  constexpr double kGap = 2.0;
  constexpr double kTime = 1.0;
  auto cost = [&](const test::TwoBody& b) {
    const double e = b.relative_vz() + (b.depth() - kGap) / kTime;
    return 0.5 * e * e;
  };
  const std::vector<ObjectFeatures> objects = {point_object(s, 9)};
  const TermGradient g =
      leader_gap_term(kGap, kTime)->evaluate({objects, {}, {}, 9}, {s.agent_speed});
  expect_gradient(g, simulated(s, cost));
}

TEST(LeaderGapBehaviour, ClosesAGapLargerThanTheSettingAndOpensASmallerOne) {
  test::TwoBody s;  // a leader ahead at the agent's own speed
  s.point_velocity = {1.0, 0.0};
  s.agent_speed = 1.0;
  Controller c(flowsteer_following({}), 1.0, {10.0, 10.0});
  for (const double ahead : {4.0, 1.2}) {
    s.point = {ahead, 0.0};
    ObjectFeatures leader = point_object(s, 9);
    leader.status = MotionStatus::lateral;  // no expansion: same speed
    leader.foe.setConstant(std::numeric_limits<double>::quiet_NaN());
    leader.ttc_s = std::numeric_limits<double>::infinity();
    const std::vector<ObjectFeatures> objects = {leader};
    const double accel = c.step({objects, {}, {}, 9}, {1.0}).command.accel_mps2;
    EXPECT_EQ(accel > 0.0, ahead > 2.0) << "leader " << ahead << " m ahead";
  }
}

TEST(FlowsteerLaw, RefusesBadWeights) {
  FlowsteerWeights w;
  w.braking = -1.0;
  EXPECT_THROW(flowsteer_goal_reaching(w), std::invalid_argument);
  w.braking = 1.0;
  w.delta = 2.0;
  EXPECT_THROW(flowsteer_goal_reaching(w), std::invalid_argument);
  EXPECT_THROW(leader_gap_term(-1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(approach_speed_term(1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(approach_speed_term(1.0, 1.0, 0.0), std::invalid_argument);
  ClearanceOptions no_full_speed;
  no_full_speed.threats.kept_width.margin_full_speed_mps = 0.0;
  EXPECT_THROW(clearance_term(no_full_speed), std::invalid_argument);
}

}  // namespace
}  // namespace flowsteer::servo
