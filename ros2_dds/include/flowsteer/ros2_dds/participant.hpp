#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace flowsteer::ros2_dds {

// Thrown by every DDS operation that fails: the message names the topic or domain and Cyclone
// DDS's own text for the error.
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The domain ids ROS 2 accepts: 0 to 232 (DDS maps a domain to UDP ports, and 232 is the last
// whose ports fit; ROS 2's documentation keeps to 0–101 and 215–232 on Linux to stay clear of
// ephemeral ports).
inline constexpr int kMaxDomainId = 232;

// ROS_DOMAIN_ID as ROS 2 reads it: 0 when unset or empty. Throws DdsError naming the variable
// and its value when it is not a whole number from 0 to kMaxDomainId.
int domain_id_from_environment();

// Why `name` is not a ROS 2 topic name flowsteer can use, or std::nullopt when it is one: it
// starts with '/', its tokens between single '/' are letters, digits and '_' and do not start
// with a digit, and it does not end with '/'.
std::optional<std::string> topic_name_problem(std::string_view name);

// How a topic's samples are delivered (the RMW profile names of ROS 2).
enum class Reliability {
  reliable,     // rmw_qos_profile_default: cmd_vel, odometry
  best_effort,  // rmw_qos_profile_sensor_data; a best-effort reader matches writers of either
};

// QoS as ROS 2 sets it for a topic: volatile durability, keep-last history of `depth`.
struct Qos {
  Reliability reliability = Reliability::reliable;
  int depth = 10;
};

// One DDS domain participant: what a ROS 2 node is on the wire. Not copyable; the publishers
// and subscriptions made from it must not outlive it. Cyclone's configuration is CYCLONEDDS_URI's
// as usual; without one, ROS_LOCALHOST_ONLY=1 (or ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) keeps
// the participant on 127.0.0.1 as ROS 2's nodes keep theirs (discovery by unicast to 127.0.0.1).
class Participant {
 public:
  // Throws DdsError naming the domain when Cyclone DDS cannot join it, or an id out of range.
  explicit Participant(int domain_id);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  int domain_id() const { return domain_id_; }
  std::int32_t handle() const { return handle_; }

 private:
  int domain_id_;
  std::int32_t handle_;
  bool localhost_only_;
};

}  // namespace flowsteer::ros2_dds
