#pragma once

#include <cstdlib>

namespace flowsteer::ros2_dds_test {

// ROS_LOCALHOST_ONLY=1, as a ROS 2 user sets it: DDS on the loopback interface only, discovery by
// unicast to 127.0.0.1 (ros2_dds::Participant, and both peers, as ROS 2's middlewares do). The
// tests' participants find each other on any machine, multicast or not, and talk to nothing
// outside. Set before the first participant; processes started afterwards inherit it. A
// CYCLONEDDS_URI of the caller's would take precedence in Cyclone, so it is cleared.
inline void use_loopback_dds() {
  ::unsetenv("CYCLONEDDS_URI");
  ::setenv("ROS_LOCALHOST_ONLY", "1", 1);
}

}  // namespace flowsteer::ros2_dds_test
