#include "flowsteer/eval/flow_evaluation.hpp"

#include <iostream>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::eval {
namespace {

using namespace flowsteer::config;

// The exact flow's row, then DIS (medium)'s, over 40 frames of a built-in scenario at 256².
std::vector<FlowEvalRow> evaluate_dis_medium(
    const char* scenario,
    servo::SegmentationMethod segmentation = servo::SegmentationMethod::semantic) {
  FlowEvalOptions options;
  options.resolutions = {256};
  options.methods = {servo::FlowMethod::dis_medium};
  options.segmentation = segmentation;
  options.frames = 40;
  std::ostringstream log;
  return evaluate_flow(builtin_scenario(scenario), options, log);
}

// The bounds for DIS (medium) on textured rendered scenes at 256²: median TTC relative
// error within 10% and FOE error within 0.03 (normalised) on approaching objects.
TEST(FlowEvaluation, DisMediumMeetsTheTtcAndFoeBoundsOnTexturedTargets) {
  const auto rows = evaluate_dis_medium("flow_targets");
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
  // Semantic regions are the renderer's objects, pixels without flow included.
  for (const FlowEvalRow& row : rows) {
    EXPECT_EQ(row.segmentation, servo::SegmentationMethod::semantic);
    EXPECT_DOUBLE_EQ(row.object_recall_mean, 1.0);
    EXPECT_DOUBLE_EQ(row.region_purity_mean, 1.0);
  }
}

// Objects found in the flow alone are matched to the renderer's by their pixels. On exact flow
// the graph finds every approaching panel, nearly whole and nearly alone; on DIS flow, whose
// texture mask leaves most of the image without flow, it still finds most of them, with the TTC
// within the bound on those it finds. The DIS floors guard what was measured when this
// was written (73% found, recall 0.52, purity 0.79).
TEST(FlowEvaluation, FlowSegmentationIsMatchedToTheObjectsByTheirPixels) {
  const auto rows = evaluate_dis_medium("flow_targets", servo::SegmentationMethod::flow_graph_fast);
  ASSERT_EQ(rows.size(), 2U);
  print_flow_table(rows, std::cout);
  const FlowEvalRow& exact = rows[0];
  EXPECT_EQ(exact.segmentation, servo::SegmentationMethod::flow_graph_fast);
  EXPECT_GE(exact.approaching_objects, 60);
  EXPECT_EQ(exact.missed_objects, 0);
  EXPECT_GT(exact.object_recall_mean, 0.8);
  EXPECT_GT(exact.region_purity_mean, 0.95);
  EXPECT_EQ(exact.phantom_objects, 0);  // exact ground flow leaves no ground region
  EXPECT_LT(exact.ttc_relative_error_median, 1e-3);
  const FlowEvalRow& dis = rows[1];
  EXPECT_GE(3 * dis.approaching_objects, 2 * (dis.approaching_objects + dis.missed_objects));
  EXPECT_GT(dis.object_recall_mean, 0.4);
  EXPECT_GT(dis.region_purity_mean, 0.6);
  EXPECT_LE(dis.ttc_relative_error_median, 0.10);
}

// The room's walls run along the path and its boxes and cylinders are seen at a slant: without
// depth the radial model reads such a surface as expanding from its near end. The test for a
// static surface gives them the heading as FOE and their TTC about it; without it the exact
// flow's own fit erred by 0.19 in FOE and 23% in TTC here, and DIS by 25% in TTC.
TEST(FlowEvaluation, StaticSurfacesWithoutDepthKeepTheHeadingAsFoe) {
  const auto rows = evaluate_dis_medium("room");
  ASSERT_EQ(rows.size(), 2U);
  const FlowEvalRow& exact = rows[0];
  EXPECT_GE(exact.approaching_objects, 100);
  EXPECT_LT(exact.foe_error_median, 0.01);
  EXPECT_LT(exact.ttc_relative_error_median, 0.05);
  const FlowEvalRow& dis = rows[1];
  EXPECT_LT(dis.foe_error_median, 0.01);
  EXPECT_LE(dis.ttc_relative_error_median, 0.15);
}

// The obstacle memory's recalled objects are placed in the world by the walker's pose and scored
// by what stands there. Along the corridor's walls with exact flow every one is on a wall: the
// scoring's frames and signs agree with the memory's. Over 60 frames the exact flow recalls about
// a hundred objects, and DIS's recalls fall in more than one of the three counts.
TEST(FlowEvaluation, RecalledObjectsAreScoredByWhatStandsWhereTheyAre) {
  FlowEvalOptions options;
  options.resolutions = {128};
  options.methods = {servo::FlowMethod::dis_ultrafast};
  options.segmentation = servo::SegmentationMethod::flow_graph_fast;
  options.obstacle_memory = true;
  options.frames = 60;
  std::ostringstream log;
  const auto rows = evaluate_flow(builtin_scenario("corridor"), options, log);
  ASSERT_EQ(rows.size(), 2U);
  const FlowEvalRow& exact = rows[0];
  EXPECT_GT(exact.recalled_objects, 20);
  EXPECT_EQ(exact.recalled_on_obstacles, exact.recalled_objects);
  for (const FlowEvalRow& row : rows) {
    EXPECT_EQ(row.recalled_on_obstacles + row.recalled_on_movers + row.recalled_on_nothing,
              row.recalled_objects);
  }
  // Without the memory nothing is recalled.
  options.obstacle_memory = false;
  options.frames = 10;
  for (const FlowEvalRow& row : evaluate_flow(builtin_scenario("corridor"), options, log)) {
    EXPECT_EQ(row.recalled_objects, 0);
  }
}

}  // namespace
}  // namespace flowsteer::eval
