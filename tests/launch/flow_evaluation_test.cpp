#include "flowsteer/launch/flow_evaluation.hpp"

#include <sstream>

#include <gtest/gtest.h>

#include "flowsteer/launch/scenario_file.hpp"

namespace flowsteer::launch {
namespace {

// The bounds for DIS (medium) on textured rendered scenes at 256²: median TTC relative
// error within 10% and FOE error within 0.03 (normalised) on approaching objects.
TEST(FlowEvaluation, DisMediumMeetsTheTtcAndFoeBoundsOnTexturedTargets) {
  FlowEvalOptions options;
  options.resolutions = {256};
  options.methods = {servo::FlowMethod::dis_medium};
  options.frames = 40;
  std::ostringstream log;
  const auto rows = evaluate_flow(builtin_scenario("flow_targets"), options, log);
  ASSERT_EQ(rows.size(), 2U);  // the synthetic reference, then DIS
  const FlowEvalRow& reference = rows[0];
  EXPECT_EQ(reference.method, servo::FlowMethod::synthetic);
  // On exact flow the fit is exact on these panels: the bounds measure the estimator.
  EXPECT_LT(reference.ttc_relative_error_median, 1e-3);
  const FlowEvalRow& dis = rows[1];
  EXPECT_EQ(dis.method, servo::FlowMethod::dis_medium);
  EXPECT_GE(dis.approaching_objects, 60);
  EXPECT_LE(dis.missed_objects, dis.approaching_objects / 10);
  EXPECT_LE(dis.ttc_relative_error_median, 0.10);
  EXPECT_LE(dis.foe_error_median, 0.03);
  EXPECT_GT(dis.valid_fraction, 0.3);
  EXPECT_GT(dis.ms_per_frame, 0.0);
}

}  // namespace
}  // namespace flowsteer::launch
