#include "dds_entities.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string_view>

namespace flowsteer::ros2_dds {

namespace detail {

dds_return_t check(dds_return_t code, const char* what, const std::string& subject) {
  if (code < 0) {
    throw DdsError(what + subject + ": " + dds_strretcode(code));
  }
  return code;
}

dds_entity_t check_entity(dds_entity_t entity, const char* what, const std::string& subject) {
  return check(entity, what, subject);
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
      "topic ",
      ros_topic + " (" + type.m_typename + ", domain " + std::to_string(participant.domain_id()) +
          ")");
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

namespace {

// Localhost only as ROS 2's middlewares take it: DDS on 127.0.0.1 only. The loopback interface
// may carry no multicast, so discovery goes by unicast to 127.0.0.1's participants.
constexpr const char* kLocalhostOnlyConfig =
    "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>32"
    "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
    "</Domain></CycloneDDS>";

// ROS_LOCALHOST_ONLY=1 (Humble, Iron) or ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST (Jazzy on).
bool localhost_only() {
  const auto is = [](const char* variable, std::string_view value) {
    const char* set = std::getenv(variable);
    return set != nullptr && std::string_view(set) == value;
  };
  // A configuration of the user's own (CYCLONEDDS_URI) is theirs to keep.
  return (is("ROS_LOCALHOST_ONLY", "1") || is("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")) &&
         std::getenv("CYCLONEDDS_URI") == nullptr;
}

// The domains made with the localhost configuration, each deleted with its last participant
// (Cyclone deletes an explicit domain with everything in it, so not before).
struct LocalhostDomain {
  dds_entity_t handle = 0;
  int participants = 0;
};
std::mutex g_domains_mutex;
std::map<int, LocalhostDomain> g_domains;

void join_localhost_domain(int domain_id) {
  const std::lock_guard lock(g_domains_mutex);
  LocalhostDomain& domain = g_domains[domain_id];
  if (domain.participants == 0) {
    const dds_entity_t handle =
        dds_create_domain(static_cast<dds_domainid_t>(domain_id), kLocalhostOnlyConfig);
    if (handle < 0) {
      g_domains.erase(domain_id);
      detail::check(handle, "domain ", std::to_string(domain_id) + " on 127.0.0.1 only");
    }
    domain.handle = handle;
  }
  ++domain.participants;
}

void leave_localhost_domain(int domain_id) {
  const std::lock_guard lock(g_domains_mutex);
  const auto found = g_domains.find(domain_id);
  if (found != g_domains.end() && --found->second.participants == 0) {
    detail::delete_entity(found->second.handle);
    g_domains.erase(found);
  }
}

}  // namespace

Participant::Participant(int domain_id)
    : domain_id_(domain_id), handle_(0), localhost_only_(localhost_only()) {
  if (domain_id < 0 || domain_id > kMaxDomainId) {
    throw DdsError("domain id " + std::to_string(domain_id) + ": not from 0 to " +
                   std::to_string(kMaxDomainId));
  }
  if (localhost_only_) {
    join_localhost_domain(domain_id);
  }
  handle_ = dds_create_participant(static_cast<dds_domainid_t>(domain_id), nullptr, nullptr);
  if (handle_ < 0 && localhost_only_) {
    leave_localhost_domain(domain_id);
  }
  detail::check_entity(handle_, "DDS participant on domain ", std::to_string(domain_id));
}

Participant::~Participant() {
  detail::delete_entity(handle_);
  if (localhost_only_) {
    leave_localhost_domain(domain_id_);
  }
}

}  // namespace flowsteer::ros2_dds
