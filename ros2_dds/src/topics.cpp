#include "flowsteer/ros2_dds/topics.hpp"

#include <chrono>
#include <thread>

#include "dds_entities.hpp"
#include "flowsteer/base/clock.hpp"
#include "message_conversions.hpp"

namespace flowsteer::ros2_dds {

namespace ros2 = recording::ros2;
using detail::check;
using detail::check_entity;
using detail::Wire;

namespace {

// Polls `done` every 5 ms until it holds or timeout_s has passed (matching happens in
// Cyclone's own threads; no status condition is worth a waitset for a start-up wait).
template <typename Done>
bool poll_until(double timeout_s, Done done) {
  const double deadline_s = base::monotonic_now_s() + timeout_s;
  while (!done()) {
    if (base::monotonic_now_s() >= deadline_s) {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace

template <typename Message>
std::string ros2_type_name() {
  return Wire<Message>::kRos2Name;
}

template <typename Message>
Publisher<Message>::Publisher(const Participant& participant, const std::string& topic,
                              const Qos& qos)
    : topic_(topic),
      topic_handle_(detail::make_topic(participant, Wire<Message>::descriptor(), topic)),
      writer_(0) {
  const detail::QosPolicy policy(qos);
  try {
    writer_ =
        check_entity(dds_create_writer(participant.handle(), topic_handle_, policy.get(), nullptr),
                     "writer on ", topic_);
  } catch (...) {
    detail::delete_entity(topic_handle_);
    throw;
  }
}

template <typename Message>
Publisher<Message>::~Publisher() {
  detail::delete_entity(writer_);
  detail::delete_entity(topic_handle_);
}

template <typename Message>
void Publisher<Message>::publish(const Message& message) {
  typename Wire<Message>::C wire{};
  Wire<Message>::to_wire(message, wire);
  check(dds_write(writer_, &wire), "publishing on ", topic_);
}

template <typename Message>
int Publisher<Message>::subscriber_count() const {
  dds_publication_matched_status_t status{};
  check(dds_get_publication_matched_status(writer_, &status), "matched subscriptions of ", topic_);
  return static_cast<int>(status.current_count);
}

template <typename Message>
bool Publisher<Message>::wait_for_subscriber(double timeout_s) const {
  return poll_until(timeout_s, [this] { return subscriber_count() > 0; });
}

template <typename Message>
bool Publisher<Message>::wait_for_acknowledgements(double timeout_s) const {
  const dds_return_t code = dds_wait_for_acks(writer_, detail::to_duration(timeout_s));
  if (code == DDS_RETCODE_TIMEOUT) {
    return false;
  }
  check(code, "waiting for acknowledgements on ", topic_);
  return true;
}

template <typename Message>
Subscription<Message>::Subscription(const Participant& participant, const std::string& topic,
                                    const Qos& qos)
    : topic_(topic),
      topic_handle_(detail::make_topic(participant, Wire<Message>::descriptor(), topic)),
      reader_(0),
      waitset_(0) {
  const detail::QosPolicy policy(qos);
  try {
    reader_ =
        check_entity(dds_create_reader(participant.handle(), topic_handle_, policy.get(), nullptr),
                     "reader on ", topic_);
    waitset_ = check_entity(dds_create_waitset(participant.handle()), "waitset for ", topic_);
    // A read condition stays triggered while any sample is in the reader's cache, so a wait
    // after taking one of several returns at once.
    const dds_entity_t has_samples =
        check_entity(dds_create_readcondition(reader_, DDS_ANY_STATE), "condition on ", topic_);
    check(dds_waitset_attach(waitset_, has_samples, 0), "waitset for ", topic_);
  } catch (...) {
    detail::delete_entity(waitset_);
    detail::delete_entity(reader_);
    detail::delete_entity(topic_handle_);
    throw;
  }
}

template <typename Message>
Subscription<Message>::~Subscription() {
  detail::delete_entity(waitset_);
  detail::delete_entity(reader_);
  detail::delete_entity(topic_handle_);
}

template <typename Message>
bool Subscription<Message>::wait(double timeout_s) {
  const dds_return_t triggered =
      dds_waitset_wait(waitset_, nullptr, 0, detail::to_duration(timeout_s));
  return check(triggered, "waiting on ", topic_) > 0;
}

template <typename Message>
bool Subscription<Message>::take(Message& message) {
  // Samples that carry no data (a writer gone) are taken and skipped.
  for (;;) {
    void* sample = nullptr;
    dds_sample_info_t info{};
    const dds_return_t count =
        check(dds_take(reader_, &sample, &info, 1, 1), "taking from ", topic_);
    if (count == 0) {
      return false;
    }
    if (info.valid_data) {
      Wire<Message>::from_wire(*static_cast<const typename Wire<Message>::C*>(sample), message);
    }
    dds_return_loan(reader_, &sample, count);
    if (info.valid_data) {
      return true;
    }
  }
}

template <typename Message>
int Subscription<Message>::publisher_count() const {
  dds_subscription_matched_status_t status{};
  check(dds_get_subscription_matched_status(reader_, &status), "matched publishers of ", topic_);
  return static_cast<int>(status.current_count);
}

#define FLOWSTEER_ROS2_TOPIC(Message)             \
  template std::string ros2_type_name<Message>(); \
  template class Publisher<Message>;              \
  template class Subscription<Message>

FLOWSTEER_ROS2_TOPIC(ros2::Twist);
FLOWSTEER_ROS2_TOPIC(TwistStamped);
FLOWSTEER_ROS2_TOPIC(ros2::Odometry);
FLOWSTEER_ROS2_TOPIC(ros2::Image);
FLOWSTEER_ROS2_TOPIC(ros2::CompressedImage);
FLOWSTEER_ROS2_TOPIC(ros2::CameraInfo);

#undef FLOWSTEER_ROS2_TOPIC

}  // namespace flowsteer::ros2_dds
