// Pins the feature dynamics of dynamics.hpp against finite differences of a two-body
// simulation (docs/CONVENTIONS.md, "Signs").
#include "flowsteer/servo/dynamics.hpp"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "two_body.hpp"

namespace flowsteer::servo {
namespace {

using test::rate_of;
using test::TwoBody;

struct Controls {
  double accel;
  double turn;
};
constexpr Controls kControls[] = {{0.0, 0.0}, {0.7, 0.0}, {0.0, 0.4}, {-0.5, -0.3}};

std::vector<TwoBody> random_configurations() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<TwoBody> out;
  while (out.size() < 40) {
    TwoBody s;
    s.agent_position = {3.0 * unit(rng), 3.0 * unit(rng)};
    s.agent_yaw = 3.0 * unit(rng);
    s.agent_speed = 1.25 + 0.75 * unit(rng);
    const double range = 6.5 + 3.5 * unit(rng);
    const double bearing = 0.5 * unit(rng);
    s.point = s.agent_position + range * Eigen::Vector2d(std::cos(s.agent_yaw + bearing),
                                                         std::sin(s.agent_yaw + bearing));
    s.point_velocity = {1.5 * unit(rng), 1.5 * unit(rng)};
    if (std::abs(s.relative_vz()) > 0.2) {  // FOE and τ need some motion along the axis
      out.push_back(s);
    }
  }
  return out;
}

void expect_rate(const FeatureRate& rate, double measured, const Controls& c, const char* what) {
  const double predicted = rate.at(c.accel, c.turn);
  EXPECT_NEAR(predicted, measured, 1e-4 * (1.0 + std::abs(measured)))
      << what << " at a_c=" << c.accel << " omega=" << c.turn;
}

TEST(FeatureDynamics, GoalRateMatchesSimulation) {
  for (TwoBody s : random_configurations()) {
    s.point_velocity.setZero();  // a goal is a static point
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.image_x(); });
      expect_rate(goal_x_rate(s.image_x(), s.depth() / s.agent_speed), measured, c, "t_x");
    }
  }
}

TEST(FeatureDynamics, GoalBearingRateMatchesSimulation) {
  for (TwoBody s : random_configurations()) {
    s.point_velocity.setZero();
    const double distance = (s.point - s.agent_position).norm();
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return std::atan(b.image_x()); });
      expect_rate(goal_bearing_rate(std::atan(s.image_x()), distance, s.agent_speed), measured, c,
                  "theta");
    }
  }
}

TEST(FeatureDynamics, CentreRateMatchesSimulation) {
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.image_x(); });
      expect_rate(centre_x_rate(s.image_x(), s.foe_x(), s.ttc()), measured, c, "g_x");
    }
  }
}

TEST(FeatureDynamics, FoeRateMatchesSimulation) {
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.foe_x(); });
      expect_rate(foe_x_rate(s.foe_x(), s.agent_speed, s.relative_vz()), measured, c, "f_x");
    }
  }
}

TEST(FeatureDynamics, SeparationRateMatchesSimulation) {
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.image_x() - b.foe_x(); });
      expect_rate(
          separation_rate(s.image_x(), s.foe_x(), s.ttc(), s.ttc() / s.depth(), s.agent_speed),
          measured, c, "delta_x");
    }
  }
}

TEST(FeatureDynamics, FlowRateMatchesSimulation) {
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.flow_x(); });
      // τ of the point itself: −Z / v_z.
      expect_rate(flow_x_rate(s.image_x(), s.flow_x(), s.ttc(), s.depth(), s.agent_speed), measured,
                  c, "u");
    }
  }
}

TEST(FeatureDynamics, InverseTtcRateMatchesSimulation) {
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return 1.0 / b.ttc(); });
      expect_rate(inverse_ttc_rate(s.image_x(), s.foe_x(), s.ttc(), s.ttc() / s.depth()), measured,
                  c, "1/tau");
    }
  }
}

TEST(FeatureDynamics, GapErrorRateMatchesSimulation) {
  constexpr double kGap = 2.0;
  constexpr double kGapTime = 1.5;
  auto gap_error = [](const TwoBody& b) { return b.relative_vz() + (b.depth() - kGap) / kGapTime; };
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      expect_rate(
          gap_error_rate(s.relative_vx(), s.relative_vz(), s.image_x(), s.depth(), kGapTime),
          rate_of(s, c.accel, c.turn, gap_error), c, "gap error");
    }
  }
}

TEST(FeatureDynamics, RelativeSpeedRateMatchesSimulation) {
  for (const TwoBody& s : random_configurations()) {
    for (const Controls& c : kControls) {
      const double measured =
          rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.relative_vz(); });
      expect_rate(relative_vz_rate(s.relative_vx()), measured, c, "v_z");
    }
  }
}

// The printed CGF Eq. 4 has ḟ = (v_c/v_z − f² − 1) ω − (f/v_z) a_c; the simulation tells it
// apart from the corrected form, so the test above is not passing by accident.
TEST(FeatureDynamics, PrintedFoeEquationDisagreesWithSimulation) {
  int disagreements = 0;
  for (const TwoBody& s : random_configurations()) {
    const Controls c{0.5, 0.3};
    const double measured = rate_of(s, c.accel, c.turn, [](const TwoBody& b) { return b.foe_x(); });
    const double f = s.foe_x();
    const double vz = s.relative_vz();
    const double printed = (s.agent_speed / vz - f * f - 1.0) * c.turn - f / vz * c.accel;
    if (std::abs(printed - measured) > 1e-3 * (1.0 + std::abs(measured))) {
      ++disagreements;
    }
  }
  EXPECT_GT(disagreements, 30);
}

}  // namespace
}  // namespace flowsteer::servo
