#pragma once

#include <cstdlib>

namespace flowsteer::ros2_dds_test {

// Cyclone DDS on the loopback interface only, discovery by unicast to 127.0.0.1: the tests'
// participants find each other on any machine, multicast or not, and talk to nothing outside.
// Set before the first participant; processes started afterwards inherit it.
inline void use_loopback_dds() {
  ::setenv("CYCLONEDDS_URI",
           "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
           "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
           "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20"
           "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
           "</Domain></CycloneDDS>",
           1);
}

}  // namespace flowsteer::ros2_dds_test
