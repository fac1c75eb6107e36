#include "dds_entities.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string_view>

namespace flowsteer::ros2_dds {

namespace detail {

dds_return_t check(dds_return_t code, const std::string& what) {
  if (code < 0) {
    throw DdsError(what + ": " + dds_strretcode(code));
  }
  return code;
}

dds_entity_t check_entity(dds_entity_t entity, const std::string& what) {
  return check(entity, what);
}

void delete_entity(dds_entity_t entity) {
  if (entity > 0) {
    dds_delete(entity);
  }
}

dds_entity_t make_topic(const Participant& participant, const dds_topic_descriptor_t& type,
                        const std::string& ros_topic) {
  if (const auto problem = topic_name_problem(ros_topic)) {
    throw DdsError("topic '" + ros_topic + "': " + *problem);
  }
  return check_entity(
      dds_create_topic(participant.handle(), &type, ("rt" + ros_topic).c_str(), nullptr, nullptr),
      "topic " + ros_topic + " (" + type.m_typename + ", domain " +
          std::to_string(participant.domain_id()) + ")");
}

QosPolicy::QosPolicy(const Qos& qos) : qos_(dds_create_qos()) {
  if (qos.reliability == Reliability::reliable) {
    dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  } else {
    dds_qset_reliability(qos_, DDS_RELIABILITY_BEST_EFFORT, 0);
  }
  dds_qset_durability(qos_, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, qos.depth);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos_, 1, &xcdr1);
}

dds_duration_t to_duration(double seconds) {
  return static_cast<dds_duration_t>(std::llround(std::max(0.0, seconds) * 1e9));
}

}  // namespace detail

int domain_id_from_environment() {
  const char* text = std::getenv("ROS_DOMAIN_ID");
  if (text == nullptr || *text == '\0') {
    return 0;
  }
  const std::string_view value(text);
  const bool digits = value.size() <= 3 && std::all_of(value.begin(), value.end(), [](char c) {
                        return std::isdigit(static_cast<unsigned char>(c));
                      });
  const int id = digits ? std::atoi(text) : -1;
  if (id < 0 || id > kMaxDomainId) {
    throw DdsError("ROS_DOMAIN_ID='" + std::string(value) + "': not a domain id from 0 to " +
                   std::to_string(kMaxDomainId));
  }
  return id;
}

std::optional<std::string> topic_name_problem(std::string_view name) {
  if (name.empty() || name.front() != '/') {
    return "a topic name starts with '/'";
  }
  if (name.size() == 1 || name.back() == '/') {
    return "a topic name does not end with '/'";
  }
  std::size_t token_start = 1;
  for (std::size_t i = 1; i <= name.size(); ++i) {
    if (i == name.size() || name[i] == '/') {
      if (i == token_start) {
        return "a topic name has no empty part ('//')";
      }
      if (std::isdigit(static_cast<unsigned char>(name[token_start]))) {
        return "a part of a topic name does not start with a digit";
      }
      token_start = i + 1;
    } else if (!std::isalnum(static_cast<unsigned char>(name[i])) && name[i] != '_') {
      return std::string("'") + name[i] +
             "' is not allowed in a topic name (letters, digits, '_', '/')";
    }
  }
  return std::nullopt;
}

Participant::Participant(int domain_id) : domain_id_(domain_id), handle_(0) {
  if (domain_id < 0 || domain_id > kMaxDomainId) {
    throw DdsError("domain id " + std::to_string(domain_id) + ": not from 0 to " +
                   std::to_string(kMaxDomainId));
  }
  handle_ = detail::check_entity(
      dds_create_participant(static_cast<dds_domainid_t>(domain_id), nullptr, nullptr),
      "DDS participant on domain " + std::to_string(domain_id));
}

Participant::~Participant() {
  detail::delete_entity(handle_);
}

}  // namespace flowsteer::ros2_dds
