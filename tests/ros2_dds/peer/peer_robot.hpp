#pragma once

// What both peers (ros2_robot_peer.cpp on Cyclone DDS, ros2_robot_peer_fastdds.cpp on Fast DDS)
// share apart from their DDS: the options, the record, the base and the camera's picture. The
// messages themselves each peer defines on its own, from ROS 2's definitions.

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

namespace peer {

inline volatile std::sig_atomic_t g_stop = 0;

inline void stop_on_signals() {
  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });
}

inline double realtime_s() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// A ROS 2 stamp (builtin_interfaces/Time) of now.
struct Stamp {
  std::int32_t sec;
  std::uint32_t nanosec;
};
inline Stamp stamp_now() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return {static_cast<std::int32_t>(t.tv_sec), static_cast<std::uint32_t>(t.tv_nsec)};
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

inline Options parse(int argc, char** argv) {
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

// The robot: a base that obeys each command at once, a camera 160x120 (focal length kFocal_px,
// 77° wide) looking at a wall
// of grey blocks 10 cm wide 4 m ahead, which looms as the base drives towards it, with a
// camera's noise (±3 grey levels, new each frame: no two images are the same). Every command is
// recorded with the realtime clock, one line each, flushed:
//   cmd,<time_s>,<linear.x>,<angular.z>
//   event,<time_s>,<what>   (moving: the first non-zero command; silent camera|odom)
class Robot {
 public:
  static constexpr int kWidth = 160;
  static constexpr int kHeight = 120;
  static constexpr double kFocal_px = 100.0;  // what its CameraInfo says

  explicit Robot(const Options& options)
      : options_(options),
        channels_(options.encoding == "rgb8" || options.encoding == "bgr8" ? 3 : 1),
        pixels_(static_cast<std::size_t>(kWidth) * kHeight * channels_),
        record_(std::fopen(options.record.c_str(), "w")),
        start_s_(realtime_s()),
        last_odom_s_(start_s_),
        next_image_s_(start_s_) {
    if (record_ == nullptr) {
      std::perror(options.record.c_str());
      std::exit(2);
    }
  }
  ~Robot() { std::fclose(record_); }

  bool running() const { return !g_stop && realtime_s() - start_s_ < options_.duration_s; }

  void command(double linear, double angular) {
    const double now_s = realtime_s();
    v_ = linear;
    w_ = angular;
    std::fprintf(record_, "cmd,%.6f,%.9g,%.9g\n", now_s, v_, w_);
    if (moving_s_ < 0.0 && (v_ != 0.0 || w_ != 0.0)) {
      moving_s_ = now_s;
      std::fprintf(record_, "event,%.6f,moving\n", now_s);
    }
    std::fflush(record_);
  }

  // Advances the clock; true when odometry (50 Hz) or an image (15 Hz) is due and not silenced.
  void tick() {
    const double now_s = realtime_s();
    if (!silenced_ && !options_.silence.empty() && moving_s_ >= 0.0 &&
        now_s - moving_s_ >= options_.silence_after_s) {
      silenced_ = true;
      std::fprintf(record_, "event,%.6f,silent %s\n", now_s, options_.silence.c_str());
      std::fflush(record_);
    }
    odometry_due_ = false;
    if (now_s - last_odom_s_ >= 0.02) {
      const double dt = now_s - last_odom_s_;
      last_odom_s_ = now_s;
      const double mid = yaw_ + 0.5 * w_ * dt;
      x_ += v_ * std::cos(mid) * dt;
      y_ += v_ * std::sin(mid) * dt;
      yaw_ += w_ * dt;
      odometry_due_ = !(silenced_ && options_.silence == "odom");
    }
    image_due_ = false;
    if (now_s >= next_image_s_) {
      next_image_s_ += 1.0 / 15.0;
      image_due_ = !(silenced_ && options_.silence == "camera");
      if (image_due_) {
        render(std::max(1.5, 4.0 - x_));
      }
    }
  }

  bool odometry_due() const { return odometry_due_; }
  bool image_due() const { return image_due_; }
  double x() const { return x_; }
  double y() const { return y_; }
  double yaw() const { return yaw_; }
  double v() const { return v_; }
  double w() const { return w_; }
  int channels() const { return channels_; }
  std::vector<std::uint8_t>& pixels() { return pixels_; }

 private:
  void render(double distance_m) {
    const double f_px = kFocal_px;
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) {
        const double x_m = (u + 0.5 - 0.5 * kWidth) / f_px * distance_m;
        const double y_m = (v + 0.5 - 0.5 * kHeight) / f_px * distance_m;
        const auto bx = static_cast<unsigned>(static_cast<int>(std::floor(x_m / 0.1)) + 100000);
        const auto by = static_cast<unsigned>(static_cast<int>(std::floor(y_m / 0.1)) + 100000);
        unsigned h = bx * 73856093u ^ by * 19349663u;
        h ^= h >> 13;
        h *= 0x5bd1e995u;
        h ^= h >> 15;
        noise_ = noise_ * 1664525u + 1013904223u;
        const auto grey = static_cast<std::uint8_t>(40 + h % 180 + (noise_ >> 29) - 3);
        for (int c = 0; c < channels_; ++c) {
          pixels_[(static_cast<std::size_t>(v) * kWidth + u) * channels_ + c] = grey;
        }
      }
    }
  }

  Options options_;
  int channels_;
  std::vector<std::uint8_t> pixels_;
  std::FILE* record_;
  double start_s_;
  double last_odom_s_;
  double next_image_s_;
  double moving_s_ = -1.0;
  bool silenced_ = false;
  bool odometry_due_ = false;
  bool image_due_ = false;
  double x_ = 0.0, y_ = 0.0, yaw_ = 0.0, v_ = 0.0, w_ = 0.0;
  unsigned noise_ = 1;
};

}  // namespace peer
