// Plays a ROS 2 robot on eProsima Fast DDS (Debian's libfastrtps 2.9, the default middleware of
// ROS 2 Humble and Jazzy), as ros2_robot_peer.cpp does on Cyclone DDS: another DDS
// implementation, as a robot running rmw_fastrtps has. Its messages are serialised here with
// Fast CDR from ROS 2's definitions (plain CDR, fields in order), under ROS 2's DDS type names;
// the robot itself and the record are peer_robot.hpp's. Same usage as ros2_robot_peer.

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <array>
#include <functional>
#include <thread>

#include "peer_robot.hpp"

namespace {

using namespace eprosima::fastdds::dds;
using eprosima::fastcdr::Cdr;
using eprosima::fastrtps::rtps::SerializedPayload_t;

// ROS 2's messages, as their .msg files define them (only what this robot sends or takes).
struct Header {
  peer::Stamp stamp{};
  std::string frame_id;
};
struct Twist {  // geometry_msgs/Twist: Vector3 linear, Vector3 angular
  std::array<double, 3> linear{};
  std::array<double, 3> angular{};
};
struct TwistStamped {
  Header header;
  Twist twist;
};
struct Odometry {  // nav_msgs/Odometry
  Header header;
  std::string child_frame_id;
  std::array<double, 3> position{};
  std::array<double, 4> orientation{};  // x, y, z, w
  std::array<double, 36> pose_covariance{};
  Twist twist;
  std::array<double, 36> twist_covariance{};
};
struct Image {  // sensor_msgs/Image
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string encoding;
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;
  std::vector<std::uint8_t> data;
};
struct CameraInfo {  // sensor_msgs/CameraInfo
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{}, r{};
  std::array<double, 12> p{};
  std::uint32_t binning_x = 0, binning_y = 0;
  std::uint32_t roi_x_offset = 0, roi_y_offset = 0, roi_height = 0, roi_width = 0;
  bool roi_do_rectify = false;
};

void put(Cdr& c, const Header& h) {
  c << h.stamp.sec << h.stamp.nanosec << h.frame_id;
}
void get(Cdr& c, Header& h) {
  c >> h.stamp.sec >> h.stamp.nanosec >> h.frame_id;
}
template <std::size_t N>
void put(Cdr& c, const std::array<double, N>& a) {
  for (double v : a)
    c << v;
}
template <std::size_t N>
void get(Cdr& c, std::array<double, N>& a) {
  for (double& v : a)
    c >> v;
}
void put(Cdr& c, const Twist& t) {
  put(c, t.linear), put(c, t.angular);
}
void get(Cdr& c, Twist& t) {
  get(c, t.linear), get(c, t.angular);
}
void put(Cdr& c, const TwistStamped& t) {
  put(c, t.header), put(c, t.twist);
}
void get(Cdr& c, TwistStamped& t) {
  get(c, t.header), get(c, t.twist);
}
void put(Cdr& c, const Odometry& o) {
  put(c, o.header);
  c << o.child_frame_id;
  put(c, o.position), put(c, o.orientation), put(c, o.pose_covariance);
  put(c, o.twist), put(c, o.twist_covariance);
}
void put(Cdr& c, const Image& i) {
  put(c, i.header);
  c << i.height << i.width << i.encoding << i.is_bigendian << i.step << i.data;
}
void put(Cdr& c, const CameraInfo& i) {
  put(c, i.header);
  c << i.height << i.width << i.distortion_model << i.d;
  put(c, i.k), put(c, i.r), put(c, i.p);
  c << i.binning_x << i.binning_y << i.roi_x_offset << i.roi_y_offset << i.roi_height << i.roi_width
    << i.roi_do_rectify;
}

// A type under its ROS 2 DDS name, in plain CDR with its encapsulation header.
template <typename T>
class RosType : public TopicDataType {
 public:
  RosType(const char* dds_name, std::uint32_t max_size) {
    setName(dds_name);
    m_typeSize = max_size;
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, SerializedPayload_t* payload) override {
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    Cdr cdr(buffer, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR);
    payload->encapsulation = cdr.endianness() == Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    cdr.serialize_encapsulation();
    put(cdr, *static_cast<const T*>(data));
    payload->length = static_cast<std::uint32_t>(cdr.getSerializedDataLength());
    return true;
  }
  // Only what the robot takes (the commands) is ever read.
  bool deserialize(SerializedPayload_t* payload, void* data) override {
    if constexpr (requires(Cdr & c, T & t) { get(c, t); }) {
      eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
      Cdr cdr(buffer, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR);
      cdr.read_encapsulation();
      get(cdr, *static_cast<T*>(data));
      return true;
    } else {
      return false;
    }
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void*) override {
    return [this] { return m_typeSize; };
  }
  void* createData() override { return new T(); }
  void deleteData(void* data) override { delete static_cast<T*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

Topic* topic(DomainParticipant* participant, TopicDataType* type, const char* ros_topic) {
  TypeSupport support(type);
  support.register_type(participant);
  return participant->create_topic(std::string("rt") + ros_topic, support.get_type_name(),
                                   TOPIC_QOS_DEFAULT);
}

// ROS 2's default profile: reliable, volatile, keep last `depth`.
template <typename Qos>
Qos ros2_qos(Qos qos, int depth) {
  qos.reliability().kind = RELIABLE_RELIABILITY_QOS;
  qos.durability().kind = VOLATILE_DURABILITY_QOS;
  qos.history().kind = KEEP_LAST_HISTORY_QOS;
  qos.history().depth = depth;
  return qos;
}

// ROS_LOCALHOST_ONLY=1 as ROS 2's rmw_fastrtps takes it: UDP on 127.0.0.1 only. Discovery then
// goes by unicast to the participants of 127.0.0.1, as the loopback interface may carry no
// multicast.
DomainParticipantQos participant_qos() {
  DomainParticipantQos qos = PARTICIPANT_QOS_DEFAULT;
  const char* localhost_only = std::getenv("ROS_LOCALHOST_ONLY");
  if (localhost_only != nullptr && std::string(localhost_only) == "1") {
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    qos.transport().use_builtin_transports = false;
    qos.transport().user_transports.push_back(udp);
    eprosima::fastrtps::rtps::Locator_t localhost;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(localhost, 127, 0, 0, 1);
    qos.wire_protocol().builtin.initialPeersList.push_back(localhost);
  }
  return qos;
}

}  // namespace

int main(int argc, char** argv) {
  const peer::Options o = peer::parse(argc, argv);
  peer::stop_on_signals();
  peer::Robot robot(o);

  DomainParticipant* participant =
      DomainParticipantFactory::get_instance()->create_participant(o.domain, participant_qos());
  if (participant == nullptr) {
    std::fprintf(stderr, "peer: no Fast DDS participant on domain %d\n", o.domain);
    return 3;
  }
  Publisher* publisher = participant->create_publisher(PUBLISHER_QOS_DEFAULT);
  Subscriber* subscriber = participant->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
  const DataWriterQos writer_qos = ros2_qos(DATAWRITER_QOS_DEFAULT, 10);
  DataWriter* images = publisher->create_datawriter(
      topic(participant, new RosType<Image>("sensor_msgs::msg::dds_::Image_", 1 << 20),
            "/camera/image_raw"),
      writer_qos);
  DataWriter* infos = publisher->create_datawriter(
      topic(participant, new RosType<CameraInfo>("sensor_msgs::msg::dds_::CameraInfo_", 4096),
            "/camera/camera_info"),
      writer_qos);
  DataWriter* odometry = publisher->create_datawriter(
      topic(participant, new RosType<Odometry>("nav_msgs::msg::dds_::Odometry_", 4096), "/odom"),
      writer_qos);
  TopicDataType* command_type = o.stamped
                                    ? static_cast<TopicDataType*>(new RosType<TwistStamped>(
                                          "geometry_msgs::msg::dds_::TwistStamped_", 1024))
                                    : new RosType<Twist>("geometry_msgs::msg::dds_::Twist_", 256);
  DataReader* commands = subscriber->create_datareader(topic(participant, command_type, "/cmd_vel"),
                                                       ros2_qos(DATAREADER_QOS_DEFAULT, 10));
  if (images == nullptr || infos == nullptr || odometry == nullptr || commands == nullptr) {
    std::fprintf(stderr, "peer: Fast DDS refused a writer or reader\n");
    return 3;
  }

  while (robot.running()) {
    SampleInfo info;
    TwistStamped stamped;
    Twist twist;
    while (commands->take_next_sample(o.stamped ? static_cast<void*>(&stamped) : &twist, &info) ==
           ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) {
        const Twist& t = o.stamped ? stamped.twist : twist;
        robot.command(t.linear[0], t.angular[2]);
      }
    }
    robot.tick();
    if (robot.odometry_due()) {
      Odometry odom;
      odom.header = {peer::stamp_now(), "odom"};
      odom.child_frame_id = "base_link";
      odom.position = {robot.x(), robot.y(), 0.0};
      odom.orientation = {0.0, 0.0, std::sin(0.5 * robot.yaw()), std::cos(0.5 * robot.yaw())};
      odom.twist.linear = {robot.v(), 0.0, 0.0};
      odom.twist.angular = {0.0, 0.0, robot.w()};
      odometry->write(&odom);
    }
    if (robot.image_due()) {
      Image image;
      image.header = {peer::stamp_now(), "camera_optical"};
      image.height = peer::Robot::kHeight;
      image.width = peer::Robot::kWidth;
      image.encoding = o.encoding;
      image.step = static_cast<std::uint32_t>(peer::Robot::kWidth * robot.channels());
      image.data = robot.pixels();
      images->write(&image);
      if (o.camera_info) {
        CameraInfo camera_info;
        camera_info.header = image.header;
        camera_info.height = image.height;
        camera_info.width = image.width;
        camera_info.distortion_model = "plumb_bob";
        camera_info.d = {0.0, 0.0, 0.0, 0.0, 0.0};
        const double f = peer::Robot::kFocal_px;
        camera_info.k = {f, 0, 0.5 * image.width, 0, f, 0.5 * image.height, 0, 0, 1};
        infos->write(&camera_info);
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  participant->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant);
  return 0;
}
