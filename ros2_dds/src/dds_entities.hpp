#pragma once

#include <string>

#include <dds/dds.h>

#include "flowsteer/ros2_dds/participant.hpp"

namespace flowsteer::ros2_dds::detail {

// A return code of Cyclone DDS that is an error throws DdsError: "<what><subject>: <Cyclone's
// text>", the message made only then (the checks sit on every publish and take).
dds_return_t check(dds_return_t code, const char* what, const std::string& subject = {});
// dds_entity_t handles are return codes too: negative ones are errors.
dds_entity_t check_entity(dds_entity_t entity, const char* what, const std::string& subject = {});

// Deletes an entity and its children; errors ignored (destructors, cleanup after a failure).
void delete_entity(dds_entity_t entity);

// The DDS topic of a ROS 2 topic: "rt" + name (ROS 2's prefix for topics), the type's
// descriptor giving ROS 2's DDS type name. Throws DdsError for a name that is not a ROS 2 topic
// name or a topic Cyclone refuses.
dds_entity_t make_topic(const Participant& participant, const dds_topic_descriptor_t& type,
                        const std::string& ros_topic);

// The QoS of a reader or writer: ROS 2's for the topic, samples in XCDR1 as ROS 2 sends them.
class QosPolicy {
 public:
  explicit QosPolicy(const Qos& qos);
  ~QosPolicy() { dds_delete_qos(qos_); }
  QosPolicy(const QosPolicy&) = delete;
  QosPolicy& operator=(const QosPolicy&) = delete;
  const dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

// A duration in seconds as DDS takes it; negative ones count as zero.
dds_duration_t to_duration(double seconds);

}  // namespace flowsteer::ros2_dds::detail
