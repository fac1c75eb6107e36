// Plays a ROS 2 robot on Cyclone DDS for the tests of flowsteer's ros2 drive and camera, as its
// drivers would: a camera driver publishing sensor_msgs/Image (and CameraInfo) on
// /camera/image_raw, a diff_drive_controller taking geometry_msgs/Twist (or TwistStamped) on
// /cmd_vel and publishing nav_msgs/Odometry on /odom. Cyclone's C API with its own types
// (ros2_robot_types.idl, written from ROS 2's definitions), none of flowsteer's code; the robot
// itself and the record are peer_robot.hpp's.
//
// Usage: flowsteer_ros2_robot_peer --domain N --record FILE [--duration S] [--stamped]
//          [--camera-info] [--encoding rgb8|bgr8|mono8|bayer_rggb8]
//          [--silence camera|odom --silence-after S]   (S after the first non-zero command)

#include <dds/dds.h>

#include <cstring>

#include "peer_robot.hpp"
#include "ros2_robot_types.h"

namespace {

void check(dds_return_t rc, const char* what) {
  if (rc < 0) {
    std::fprintf(stderr, "peer: %s: %s\n", what, dds_strretcode(rc));
    std::exit(3);
  }
}

// A writer or reader on ROS 2 topic `ros_topic` ("rt" + name on DDS): volatile, keep last
// `depth`, XCDR1, as ROS 2's middlewares make them.
dds_entity_t endpoint(dds_entity_t participant, const dds_topic_descriptor_t* type,
                      const char* ros_topic, bool writer, int depth) {
  const std::string dds_name = std::string("rt") + ros_topic;
  const dds_entity_t topic =
      dds_create_topic(participant, type, dds_name.c_str(), nullptr, nullptr);
  check(topic, ros_topic);
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, depth);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos, 1, &xcdr1);
  const dds_entity_t e = writer ? dds_create_writer(participant, topic, qos, nullptr)
                                : dds_create_reader(participant, topic, qos, nullptr);
  dds_delete_qos(qos);
  check(e, ros_topic);
  return e;
}

// ROS_LOCALHOST_ONLY=1 as ROS 2's rmw_cyclonedds takes it: the loopback interface only, and
// discovery by unicast to 127.0.0.1, as it may carry no multicast.
void keep_to_localhost(int domain) {
  const char* localhost_only = std::getenv("ROS_LOCALHOST_ONLY");
  if (localhost_only != nullptr && std::string(localhost_only) == "1") {
    check(dds_create_domain(domain,
                            "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
                            "</Interfaces><AllowMulticast>false</AllowMulticast></General>"
                            "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
                            "<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex><Peers><Peer "
                            "address=\"127.0.0.1\"/></Peers></Discovery>"),
          "localhost domain");
  }
}

builtin_interfaces_msg_dds__Time_ now() {
  const peer::Stamp s = peer::stamp_now();
  return {s.sec, s.nanosec};
}

}  // namespace

int main(int argc, char** argv) {
  const peer::Options o = peer::parse(argc, argv);
  peer::stop_on_signals();
  peer::Robot robot(o);

  keep_to_localhost(o.domain);
  const dds_entity_t participant = dds_create_participant(o.domain, nullptr, nullptr);
  check(participant, "participant");
  const dds_entity_t images =
      endpoint(participant, &sensor_msgs_msg_dds__Image__desc, "/camera/image_raw", true, 2);
  const dds_entity_t infos =
      endpoint(participant, &sensor_msgs_msg_dds__CameraInfo__desc, "/camera/camera_info", true, 1);
  const dds_entity_t odometry =
      endpoint(participant, &nav_msgs_msg_dds__Odometry__desc, "/odom", true, 10);
  const dds_entity_t commands =
      o.stamped
          ? endpoint(participant, &geometry_msgs_msg_dds__TwistStamped__desc, "/cmd_vel", false, 10)
          : endpoint(participant, &geometry_msgs_msg_dds__Twist__desc, "/cmd_vel", false, 10);

  while (robot.running()) {
    for (;;) {
      void* sample = nullptr;
      dds_sample_info_t info;
      const dds_return_t n = dds_take(commands, &sample, &info, 1, 1);
      check(n, "take cmd_vel");
      if (n == 0) {
        break;
      }
      if (info.valid_data) {
        const geometry_msgs_msg_dds__Twist_& twist =
            o.stamped ? static_cast<geometry_msgs_msg_dds__TwistStamped_*>(sample)->twist
                      : *static_cast<geometry_msgs_msg_dds__Twist_*>(sample);
        robot.command(twist.linear.x, twist.angular.z);
      }
      dds_return_loan(commands, &sample, n);
    }
    robot.tick();
    if (robot.odometry_due()) {
      nav_msgs_msg_dds__Odometry_ odom{};
      odom.header.stamp = now();
      odom.header.frame_id = const_cast<char*>("odom");
      odom.child_frame_id = const_cast<char*>("base_link");
      odom.pose.pose.position = {robot.x(), robot.y(), 0.0};
      odom.pose.pose.orientation = {0.0, 0.0, std::sin(0.5 * robot.yaw()),
                                    std::cos(0.5 * robot.yaw())};
      odom.twist.twist.linear = {robot.v(), 0.0, 0.0};
      odom.twist.twist.angular = {0.0, 0.0, robot.w()};
      check(dds_write(odometry, &odom), "write odom");
    }
    if (robot.image_due()) {
      sensor_msgs_msg_dds__Image_ image{};
      image.header.stamp = now();
      image.header.frame_id = const_cast<char*>("camera_optical");
      image.height = peer::Robot::kHeight;
      image.width = peer::Robot::kWidth;
      image.encoding = const_cast<char*>(o.encoding.c_str());
      image.step = static_cast<uint32_t>(peer::Robot::kWidth * robot.channels());
      image.data._buffer = robot.pixels().data();
      image.data._length = image.data._maximum = static_cast<uint32_t>(robot.pixels().size());
      check(dds_write(images, &image), "write image");
      if (o.camera_info) {
        sensor_msgs_msg_dds__CameraInfo_ info{};
        info.header = image.header;
        info.height = image.height;
        info.width = image.width;
        info.distortion_model = const_cast<char*>("plumb_bob");
        double d[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        info.d._buffer = d;
        info.d._length = info.d._maximum = 5;
        const double f = peer::Robot::kFocal_px, cx = 0.5 * image.width, cy = 0.5 * image.height;
        const double k[9] = {f, 0, cx, 0, f, cy, 0, 0, 1};
        std::memcpy(info.k, k, sizeof k);
        check(dds_write(infos, &info), "write camera_info");
      }
    }
    dds_sleepfor(DDS_MSECS(1));
  }
  dds_delete(participant);
  return 0;
}
