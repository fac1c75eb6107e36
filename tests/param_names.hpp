#pragma once
// Names for value-parameterised tests whose parameter is a scenario's name: the test is named
// after it (Papers/GoalScenario.EveryAgentReachesItsGoalWithoutCollision/room). Every
// instantiation names its tests: ctest's names then carry no "# GetParam() = ..." comment, whose
// spaces keep ctest from matching a test to its cost of the last run (tests/CMakeLists.txt).

#include <string>

#include <gtest/gtest.h>

namespace flowsteer::test {

inline std::string scenario_param_name(const ::testing::TestParamInfo<const char*>& info) {
  return info.param;
}

}  // namespace flowsteer::test
