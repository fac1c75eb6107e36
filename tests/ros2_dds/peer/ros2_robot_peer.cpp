// Plays a ROS 2 robot for the tests of flowsteer's ros2 drive and camera, as its drivers would
// on DDS: a camera driver publishing sensor_msgs/Image (and CameraInfo), a diff_drive_controller
// taking geometry_msgs/Twist (or TwistStamped) on /cmd_vel and publishing nav_msgs/Odometry on
// /odom. Built on Cyclone DDS's C API with its own types (ros2_robot_types.idl, written from
// ROS 2's definitions), none of flowsteer's code.
//
// The base obeys each command at once and integrates its pose; the camera looks at a wall of
// random texture 4 m ahead, which looms as the base drives towards it. Every command taken
// is recorded with the realtime clock, one line each, flushed:
//   cmd,<time_s>,<linear.x>,<angular.z>
//   event,<time_s>,<what>        (moving: the first non-zero command; silent: a stream stopped)
//
// Usage: flowsteer_ros2_robot_peer --domain N --record FILE [--duration S] [--stamped]
//          [--camera-info] [--encoding rgb8|bgr8|mono8|bayer_rggb8]
//          [--silence camera|odom --silence-after S]   (S after the first non-zero command)

#include <dds/dds.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "ros2_robot_types.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;

double realtime_s() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

builtin_interfaces_msg_dds__Time_ stamp_now() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return {static_cast<int32_t>(t.tv_sec), static_cast<uint32_t>(t.tv_nsec)};
}

void check(dds_return_t rc, const char* what) {
  if (rc < 0) {
    std::fprintf(stderr, "peer: %s: %s\n", what, dds_strretcode(rc));
    std::exit(3);
  }
}

struct Options {
  int domain = 0;
  std::string record;
  double duration_s = 60.0;
  bool stamped = false;
  bool camera_info = false;
  std::string encoding = "rgb8";
  std::string silence;
  double silence_after_s = 0.0;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "peer: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--domain") {
      o.domain = std::atoi(next().c_str());
    } else if (a == "--record") {
      o.record = next();
    } else if (a == "--duration") {
      o.duration_s = std::atof(next().c_str());
    } else if (a == "--stamped") {
      o.stamped = true;
    } else if (a == "--camera-info") {
      o.camera_info = true;
    } else if (a == "--encoding") {
      o.encoding = next();
    } else if (a == "--silence") {
      o.silence = next();
    } else if (a == "--silence-after") {
      o.silence_after_s = std::atof(next().c_str());
    } else {
      std::fprintf(stderr, "peer: unknown option %s\n", a.c_str());
      std::exit(2);
    }
  }
  if (o.record.empty()) {
    std::fprintf(stderr, "peer: --record FILE is required\n");
    std::exit(2);
  }
  return o;
}

dds_qos_t* ros2_qos(bool reliable, int depth) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, depth);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos, 1, &xcdr1);
  return qos;
}

dds_entity_t endpoint(dds_entity_t participant, const dds_topic_descriptor_t* type,
                      const char* ros_topic, bool writer, bool reliable, int depth) {
  const std::string dds_name = std::string("rt") + ros_topic;
  const dds_entity_t topic =
      dds_create_topic(participant, type, dds_name.c_str(), nullptr, nullptr);
  check(topic, ros_topic);
  dds_qos_t* qos = ros2_qos(reliable, depth);
  const dds_entity_t e = writer ? dds_create_writer(participant, topic, qos, nullptr)
                                : dds_create_reader(participant, topic, qos, nullptr);
  dds_delete_qos(qos);
  check(e, ros_topic);
  return e;
}

// A wall of grey blocks 10 cm wide, seen head-on `distance_m` ahead by a 90° camera, with a
// camera's noise (±3 grey levels, new each frame: no two images are the same).
void render(std::vector<uint8_t>& pixels, int width, int height, int channels, double distance_m,
            unsigned& noise) {
  const double f_px = 0.5 * width;  // 90° horizontal field of view
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double x_m = (u + 0.5 - 0.5 * width) / f_px * distance_m;
      const double y_m = (v + 0.5 - 0.5 * height) / f_px * distance_m;
      const auto bx = static_cast<unsigned>(static_cast<int>(std::floor(x_m / 0.1)) + 100000);
      const auto by = static_cast<unsigned>(static_cast<int>(std::floor(y_m / 0.1)) + 100000);
      unsigned h = bx * 73856093u ^ by * 19349663u;
      h ^= h >> 13;
      h *= 0x5bd1e995u;
      h ^= h >> 15;
      noise = noise * 1664525u + 1013904223u;
      const auto grey = static_cast<uint8_t>(40 + h % 180 + (noise >> 29) - 3);
      for (int c = 0; c < channels; ++c) {
        pixels[(static_cast<size_t>(v) * width + u) * channels + c] = grey;
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });
  FILE* record = std::fopen(o.record.c_str(), "w");
  if (record == nullptr) {
    std::perror(o.record.c_str());
    return 2;
  }

  const dds_entity_t participant = dds_create_participant(o.domain, nullptr, nullptr);
  check(participant, "participant");
  const dds_entity_t image_writer =
      endpoint(participant, &sensor_msgs_msg_dds__Image__desc, "/camera/image_raw", true, true, 2);
  const dds_entity_t info_writer = endpoint(participant, &sensor_msgs_msg_dds__CameraInfo__desc,
                                            "/camera/camera_info", true, true, 1);
  const dds_entity_t odom_writer =
      endpoint(participant, &nav_msgs_msg_dds__Odometry__desc, "/odom", true, true, 10);
  const dds_entity_t cmd_reader =
      o.stamped
          ? endpoint(participant, &geometry_msgs_msg_dds__TwistStamped__desc, "/cmd_vel", false,
                     true, 10)
          : endpoint(participant, &geometry_msgs_msg_dds__Twist__desc, "/cmd_vel", false, true, 10);

  const int width = 160;
  const int height = 120;
  const int channels = o.encoding == "rgb8" || o.encoding == "bgr8" ? 3 : 1;
  std::vector<uint8_t> pixels(static_cast<size_t>(width) * height * channels);
  const double wall_m = 4.0;
  unsigned noise = 1;

  double x = 0.0, y = 0.0, yaw = 0.0, v = 0.0, w = 0.0;
  const double start_s = realtime_s();
  double last_odom_s = start_s, next_image_s = start_s, moving_s = -1.0;
  bool silenced = false;
  while (!g_stop && realtime_s() - start_s < o.duration_s) {
    const double now_s = realtime_s();
    // Commands: the newest is obeyed; each one is recorded.
    for (;;) {
      void* sample = nullptr;
      dds_sample_info_t info;
      const dds_return_t n = dds_take(cmd_reader, &sample, &info, 1, 1);
      check(n, "take cmd_vel");
      if (n == 0) {
        break;
      }
      if (info.valid_data) {
        const geometry_msgs_msg_dds__Twist_& twist =
            o.stamped ? static_cast<geometry_msgs_msg_dds__TwistStamped_*>(sample)->twist
                      : *static_cast<geometry_msgs_msg_dds__Twist_*>(sample);
        v = twist.linear.x;
        w = twist.angular.z;
        std::fprintf(record, "cmd,%.6f,%.9g,%.9g\n", now_s, v, w);
        if (moving_s < 0.0 && (v != 0.0 || w != 0.0)) {
          moving_s = now_s;
          std::fprintf(record, "event,%.6f,moving\n", now_s);
        }
        std::fflush(record);
      }
      dds_return_loan(cmd_reader, &sample, n);
    }
    if (!silenced && !o.silence.empty() && moving_s >= 0.0 &&
        now_s - moving_s >= o.silence_after_s) {
      silenced = true;
      std::fprintf(record, "event,%.6f,silent %s\n", now_s, o.silence.c_str());
      std::fflush(record);
    }
    // The base: 50 Hz odometry.
    if (now_s - last_odom_s >= 0.02) {
      const double dt = now_s - last_odom_s;
      last_odom_s = now_s;
      const double mid = yaw + 0.5 * w * dt;
      x += v * std::cos(mid) * dt;
      y += v * std::sin(mid) * dt;
      yaw += w * dt;
      if (!(silenced && o.silence == "odom")) {
        nav_msgs_msg_dds__Odometry_ odom{};
        odom.header.stamp = stamp_now();
        odom.header.frame_id = const_cast<char*>("odom");
        odom.child_frame_id = const_cast<char*>("base_link");
        odom.pose.pose.position = {x, y, 0.0};
        odom.pose.pose.orientation = {0.0, 0.0, std::sin(0.5 * yaw), std::cos(0.5 * yaw)};
        odom.twist.twist.linear = {v, 0.0, 0.0};
        odom.twist.twist.angular = {0.0, 0.0, w};
        check(dds_write(odom_writer, &odom), "write odom");
      }
    }
    // The camera: 15 Hz.
    if (now_s >= next_image_s) {
      next_image_s += 1.0 / 15.0;
      if (!(silenced && o.silence == "camera")) {
        render(pixels, width, height, channels, std::max(1.5, wall_m - x), noise);
        sensor_msgs_msg_dds__Image_ image{};
        image.header.stamp = stamp_now();
        image.header.frame_id = const_cast<char*>("camera_optical");
        image.height = height;
        image.width = width;
        image.encoding = const_cast<char*>(o.encoding.c_str());
        image.step = static_cast<uint32_t>(width * channels);
        image.data._buffer = pixels.data();
        image.data._length = image.data._maximum = static_cast<uint32_t>(pixels.size());
        check(dds_write(image_writer, &image), "write image");
        if (o.camera_info) {
          sensor_msgs_msg_dds__CameraInfo_ info{};
          info.header = image.header;
          info.height = height;
          info.width = width;
          info.distortion_model = const_cast<char*>("plumb_bob");
          double d[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
          info.d._buffer = d;
          info.d._length = info.d._maximum = 5;
          const double f = 0.5 * width, cx = 0.5 * width, cy = 0.5 * height;
          const double k[9] = {f, 0, cx, 0, f, cy, 0, 0, 1};
          std::memcpy(info.k, k, sizeof k);
          check(dds_write(info_writer, &info), "write camera_info");
        }
      }
    }
    dds_sleepfor(DDS_MSECS(1));
  }
  std::fclose(record);
  dds_delete(participant);
  return 0;
}
