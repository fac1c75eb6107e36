// The SteerSuite importer on small hand-written test cases.
#include <cmath>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "flowsteer/base/config_error.hpp"
#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::config {
namespace {

// A test case whose body starts on line 4, in a world from −20 to 20 on both axes.
std::string test_case(const std::string& body) {
  return "<SteerBenchTestCase>\n"
         "<header><version>1.0</version><name>t</name>\n"
         "<worldBounds><xmin>-20</xmin><xmax>20</xmax><ymin>0</ymin><ymax>0</ymax><zmin>-20</zmin>"
         "<zmax>20</zmax></worldBounds></header>\n" +
         body + "</SteerBenchTestCase>\n";
}

// One agent on one line, at SteerSuite (x, 0, z), going to (x + 5, 0, z).
std::string agent(double x, double z, const std::string& extra_initial = "",
                  const std::string& extra = "") {
  const std::string sx = std::to_string(x);
  const std::string sz = std::to_string(z);
  return "<agent><name>a</name><initialConditions><radius>0.5</radius><position><x>" + sx +
         "</x><y>0</y><z>" + sz +
         "</z></position><direction><x>1</x><y>0</y><z>0</z></direction><speed>0</speed>" +
         extra_initial + "</initialConditions><goalSequence><seekStaticTarget><targetLocation><x>" +
         std::to_string(x + 5) + "</x><y>0</y><z>" + sz +
         "</z></targetLocation><desiredSpeed>1.3</desiredSpeed></seekStaticTarget></goalSequence>" +
         extra + "</agent>\n";
}

std::string error_of(const std::string& xml) {
  try {
    parse_steersuite(xml, "case.xml");
  } catch (const base::ConfigError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(SteerSuiteImport, InvertedWorldBoundsAreAWarningNotAnError) {
  const std::string xml =
      "<SteerBenchTestCase>\n<header><name>t</name>\n"
      "<worldBounds><xmin>-100</xmin><xmax>-200</xmax><ymin>0</ymin><ymax>0</ymax>"
      "<zmin>-100</zmin><zmax>-200</zmax></worldBounds></header>\n" +
      agent(0, 0) + "</SteerBenchTestCase>\n";
  const LoadedCase loaded = parse_steersuite(xml, "case.xml");
  ASSERT_EQ(loaded.world.agents.size(), 1U);
  ASSERT_EQ(loaded.warnings.size(), 1U);
  EXPECT_TRUE(contains(loaded.warnings[0], "case.xml:3: ")) << loaded.warnings[0];
  EXPECT_TRUE(contains(loaded.warnings[0], "worldBounds")) << loaded.warnings[0];
}

std::string region_of(int count, int half_width) {
  const std::string w = std::to_string(half_width);
  return "<agentRegion><numAgents>" + std::to_string(count) + "</numAgents><regionBounds><xmin>-" +
         w + "</xmin><xmax>" + w + "</xmax><ymin>0</ymin><ymax>0</ymax><zmin>-" + w +
         "</zmin><zmax>" + w +
         "</zmax></regionBounds><initialConditions><direction><random>true</random></direction>"
         "<radius>0.5</radius></initialConditions><goalSequence><seekStaticTarget>"
         "<targetLocation><random>true</random></targetLocation><desiredSpeed>1.3</desiredSpeed>"
         "</seekStaticTarget></goalSequence></agentRegion>\n";
}

TEST(SteerSuiteImport, AgentRegionsHoldMoreThanAThousandAgentsUpToTheStatedLimit) {
  const LoadedCase loaded = parse_steersuite(test_case(region_of(1200, 40)), "case.xml");
  EXPECT_EQ(loaded.world.agents.size(), 1200U);
  for (const auto& a : loaded.world.agents) {
    ASSERT_EQ(a.goals.size(), 1U);
    // A random target is inside the world, 1 m from its edge, as SteerSuite draws it.
    EXPECT_LE(a.goals[0].cwiseAbs().maxCoeff(), 19.0);
  }
  const std::string error = error_of(test_case(region_of(10001, 40)));
  EXPECT_TRUE(contains(error, "case.xml:4:")) << error;
  EXPECT_TRUE(contains(error, "from 0 to 10000")) << error;
}

std::string obstacle_region(int count) {
  return "<obstacleRegion><numObstacles>" + std::to_string(count) +
         "</numObstacles><regionBounds><xmin>-10</xmin><xmax>10</xmax><ymin>0</ymin><ymax>0</ymax>"
         "<zmin>-10</zmin><zmax>10</zmax></regionBounds><obstacleSize>1</obstacleSize>"
         "<obstacleHeight>1.5</obstacleHeight></obstacleRegion>\n";
}

TEST(SteerSuiteImport, ObstacleRegionsArePlacedFromTheSeedClearOfAgents) {
  const std::string xml = test_case(agent(0, 0) + obstacle_region(40));
  const sim_camera::WorldSpec w = parse_steersuite(xml, "case.xml", 7).world;
  ASSERT_EQ(w.obstacles.size(), 40U);
  for (std::size_t i = 0; i < w.obstacles.size(); ++i) {
    const sim_camera::Solid& o = w.obstacles[i];
    EXPECT_EQ(o.shape, sim_camera::Solid::Shape::box);
    EXPECT_DOUBLE_EQ(o.size_m.x(), 1.0);
    EXPECT_DOUBLE_EQ(o.height_m, 1.5);
    // Inside the region shrunk by the obstacle's size, like SteerSuite.
    EXPECT_LE(o.centre_m.cwiseAbs().maxCoeff(), 9.0);
    EXPECT_GT(sim_camera::footprint_distance(o, w.agents[0].start_m), w.agents[0].radius_m);
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_GE((o.centre_m - w.obstacles[j].centre_m).cwiseAbs().maxCoeff(), 1.0);
    }
  }
  const sim_camera::WorldSpec same = parse_steersuite(xml, "case.xml", 7).world;
  const sim_camera::WorldSpec other = parse_steersuite(xml, "case.xml", 8).world;
  EXPECT_EQ(same.obstacles[5].centre_m, w.obstacles[5].centre_m);
  EXPECT_NE(other.obstacles[5].centre_m, w.obstacles[5].centre_m);
}

TEST(SteerSuiteImport, CircleObstacleIsACylinderInTheWorldFrame) {
  const sim_camera::WorldSpec w =
      parse_steersuite(
          test_case("<circleObstacle><radius>1.5</radius><height>2</height>"
                    "<position><x>3</x><y>0</y><z>4</z></position></circleObstacle>\n" +
                    agent(-10, 0)),
          "case.xml")
          .world;
  ASSERT_EQ(w.obstacles.size(), 1U);
  const sim_camera::Solid& c = w.obstacles[0];
  EXPECT_EQ(c.shape, sim_camera::Solid::Shape::cylinder);
  EXPECT_NEAR(c.centre_m.x(), 3.0, 1e-12);
  EXPECT_NEAR(c.centre_m.y(), -4.0, 1e-12);  // SteerSuite z is world −y
  EXPECT_NEAR(c.radius_m, 1.5, 1e-12);
  EXPECT_NEAR(c.height_m, 2.0, 1e-12);
}

TEST(SteerSuiteImport, OrientedBoxTurnsLikeSteerSuites) {
  const sim_camera::WorldSpec w =
      parse_steersuite(
          test_case(
              "<orientedBoxObstacle><thetaY>30</thetaY><size><x>4</x><y>1.2</y><z>2</z></size>"
              "<position><x>1</x><y>0</y><z>2</z></position></orientedBoxObstacle>\n" +
              agent(-10, 0)),
          "case.xml")
          .world;
  ASSERT_EQ(w.obstacles.size(), 1U);
  const sim_camera::Solid& box = w.obstacles[0];
  EXPECT_NEAR(box.yaw_rad, 30.0 * std::numbers::pi / 180.0, 1e-12);
  EXPECT_NEAR(box.height_m, 1.2, 1e-12);
  // SteerSuite's corner (lengthX / 2, −lengthZ / 2) turned by θ = 30° in its x–z plane
  // (x' = x cos θ + z sin θ, z' = z cos θ − x sin θ) and moved to the centre (1, 2).
  const double c = std::cos(30.0 * std::numbers::pi / 180.0);
  const double s = std::sin(30.0 * std::numbers::pi / 180.0);
  const double corner_x = 1.0 + (2.0 * c - 1.0 * s);
  const double corner_z = 2.0 + (-1.0 * c - 2.0 * s);
  const Eigen::Vector2d corner(corner_x, -corner_z);
  EXPECT_NEAR(sim_camera::footprint_distance(box, corner), 0.0, 1e-9);
  // The mirrored yaw would put that corner outside the box.
  sim_camera::Solid mirrored = box;
  mirrored.yaw_rad = -box.yaw_rad;
  EXPECT_GT(sim_camera::footprint_distance(mirrored, corner), 0.1);
}

TEST(SteerSuiteImport, UnknownElementsAreErrorsWithTheirLine) {
  const std::string at_root = error_of(test_case(agent(0, 0) + "<bogus/>\n"));
  EXPECT_TRUE(contains(at_root, "case.xml:5:")) << at_root;
  EXPECT_TRUE(contains(at_root, "<bogus>")) << at_root;
  const std::string in_agent =
      error_of(test_case(std::string("\n") + agent(0, 0, "", "<mood>calm</mood>")));
  EXPECT_TRUE(contains(in_agent, "case.xml:5:")) << in_agent;
  EXPECT_TRUE(contains(in_agent, "<mood>")) << in_agent;
  const std::string in_initial = error_of(test_case(agent(0, 0, "<mass>70</mass>")));
  EXPECT_TRUE(contains(in_initial, "case.xml:4:")) << in_initial;
  EXPECT_TRUE(contains(in_initial, "<mass> in <initialConditions>")) << in_initial;
}

TEST(SteerSuiteImport, GoalsFlowsteerCannotFollowAreErrors) {
  const std::string flee = error_of(test_case(
      agent(0, 0) +
      "<agent><initialConditions><position><x>5</x><y>0</y><z>5</z></position><direction><x>1"
      "</x><y>0</y><z>0</z></direction></initialConditions><goalSequence>\n<fleeStaticTarget>"
      "<targetLocation><x>0</x><y>0</y><z>0</z></targetLocation></fleeStaticTarget>"
      "</goalSequence></agent>\n"));
  EXPECT_TRUE(contains(flee, "case.xml:6:")) << flee;
  EXPECT_TRUE(contains(flee, "<fleeStaticTarget> is not supported")) << flee;
  const std::string short_goal = error_of(test_case(
      "<agent><initialConditions><position><x>5</x><y>0</y><z>5</z></position><direction><x>1"
      "</x><y>0</y><z>0</z></direction></initialConditions><goalSequence><seekStaticTarget>"
      "<targetLocation><x>0</x><y>0</y><z>0</z></targetLocation>\n<timeDuration>3</timeDuration>"
      "</seekStaticTarget></goalSequence></agent>\n"));
  EXPECT_TRUE(contains(short_goal, "case.xml:5:")) << short_goal;
  EXPECT_TRUE(contains(short_goal, "timeDuration")) << short_goal;
}

TEST(SteerSuiteImport, ALoneIdleGoalKeepsTheAgentWhereItStarts) {
  const LoadedCase loaded = parse_steersuite(
      test_case("<agent><initialConditions><radius>0.4</radius><position><x>5</x><y>0</y><z>5</z>"
                "</position><direction><x>0</x><y>0</y><z>1</z></direction></initialConditions>"
                "<goalSequence><idle><timeDuration>1000</timeDuration></idle></goalSequence>"
                "</agent>\n"),
      "case.xml");
  const sim_camera::AgentSpec& a = loaded.world.agents.at(0);
  ASSERT_EQ(a.goals.size(), 1U);
  EXPECT_EQ(a.goals[0], a.start_m);
  EXPECT_NEAR(a.heading_rad, -std::numbers::pi / 2, 1e-12);  // facing SteerSuite +z: world −y
}

TEST(SteerSuiteImport, ACaseIsReadByItsExtension) {
  try {
    load_case("scenario.txt");
    ADD_FAILURE() << "a .txt file was read";
  } catch (const base::ConfigError& e) {
    EXPECT_TRUE(contains(e.what(), "scenario.txt")) << e.what();
  }
  EXPECT_EQ(load_case(FLOWSTEER_CORRIDOR_CASE).world.name, "corridor");
}

}  // namespace
}  // namespace flowsteer::config
