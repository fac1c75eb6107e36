// Capture-side latency on replay at 640x480: decoding a recorded frame (MJPG in AVI, as a robot
// records), undistorting it with a calibration, and the DIS optical flow the numerical-flow
// pipeline runs on consecutive frames; then the whole capture-to-command step of `flowsteer
// run`: decode, undistort, the brain's perception (DIS flow, derotation, ground test, flow_graph_fast
// segmentation, features) and the controller's command. The recording is written at start-up:
// a textured scene sliding sideways, so that the flow has something to find.

#include <filesystem>
#include <memory>
#include <sstream>
#include <string>

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/camera_io/replay_source.hpp"
#include "flowsteer/robot/robot_brain.hpp"

namespace {

namespace fs = std::filesystem;
using flowsteer::camera_io::Frame;
using flowsteer::camera_io::ReadStatus;
using flowsteer::camera_io::ReplayOptions;
using flowsteer::camera_io::ReplaySource;

constexpr int kFrames = 120;

const std::string& recording() {
  static const std::string path = [] {
    const fs::path file = fs::temp_directory_path() / "flowsteer_camera_bench_640x480.avi";
    cv::Mat texture(480, 1280, CV_8UC3);
    cv::randu(texture, cv::Scalar::all(0), cv::Scalar::all(255));
    cv::GaussianBlur(texture, texture, {0, 0}, 3.0);
    cv::VideoWriter writer(file.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0,
                           {640, 480});
    for (int i = 0; i < kFrames; ++i) {
      writer.write(texture(cv::Rect(2 * i, 0, 640, 480)));
    }
    return file.string();
  }();
  return path;
}

ReplayOptions options(bool calibrated) {
  ReplayOptions o;
  o.path = recording();
  if (calibrated) {
    flowsteer::camera_io::CameraModel model;
    model.width_px = 640;
    model.height_px = 480;
    model.fx = model.fy = 550.0;
    model.cx = 320.0;
    model.cy = 240.0;
    model.distortion = flowsteer::camera_io::DistortionModel::plumb_bob;
    model.coefficients = {-0.25, 0.08, 0.0, 0.0, 0.0};
    o.lens.model = model;
  }
  return o;
}

// One frame read from the recording; the source reopens (untimed) at the end.
void read_frames(benchmark::State& state, bool calibrated) {
  auto source = std::make_unique<ReplaySource>(options(calibrated));
  Frame frame;
  for (auto _ : state) {
    if (source->read(frame, 0.1) != ReadStatus::ok) {
      state.PauseTiming();
      source = std::make_unique<ReplaySource>(options(calibrated));
      state.ResumeTiming();
      source->read(frame, 0.1);
    }
    benchmark::DoNotOptimize(frame.image.data);
  }
}

void BM_ReplayRead640x480(benchmark::State& state) {
  read_frames(state, false);
}
void BM_ReplayReadUndistort640x480(benchmark::State& state) {
  read_frames(state, true);
}

// Read, grey conversion and DIS flow against the previous frame: the capture side of one
// control step with numerical flow.
void BM_ReplayReadDisFlow640x480(benchmark::State& state) {
  auto source = std::make_unique<ReplaySource>(options(false));
  const auto dis = cv::DISOpticalFlow::create(static_cast<int>(state.range(0)));
  Frame frame;
  cv::Mat grey;
  cv::Mat previous;
  cv::Mat flow;
  source->read(frame, 0.1);
  cv::cvtColor(frame.image, previous, cv::COLOR_BGR2GRAY);
  for (auto _ : state) {
    if (source->read(frame, 0.1) != ReadStatus::ok) {
      // A new pass: its first frame is the previous one, so that flow is never timed across
      // the jump from the last frame back to the first.
      state.PauseTiming();
      source = std::make_unique<ReplaySource>(options(false));
      source->read(frame, 0.1);
      cv::cvtColor(frame.image, previous, cv::COLOR_BGR2GRAY);
      source->read(frame, 0.1);
      state.ResumeTiming();
    }
    cv::cvtColor(frame.image, grey, cv::COLOR_BGR2GRAY);
    dis->calc(previous, grey, flow);
    cv::swap(previous, grey);
    benchmark::DoNotOptimize(flow.data);
  }
}

// One frame from capture to command, as the robot loop runs it (the calibrated recording is
// undistorted). Counters: each stage's mean milliseconds.
void BM_CaptureToCommand640x480(benchmark::State& state) {
  flowsteer::config::PerceptionSection perception;
  perception.flow = static_cast<flowsteer::servo::FlowMethod>(state.range(0));
  perception.segmentation = flowsteer::servo::SegmentationMethod::flow_graph_fast;
  perception.mount = {0.3, 0.1};
  flowsteer::config::ControllerSection controller;
  controller.spec.use_depth = false;
  std::ostringstream log;
  std::unique_ptr<ReplaySource> source;
  std::unique_ptr<flowsteer::robot::RobotBrain> brain;
  Frame frame;
  // A fresh recording needs a first frame before there is flow; that frame is not timed.
  const auto restart = [&] {
    source = std::make_unique<ReplaySource>(options(true));
    brain = std::make_unique<flowsteer::robot::RobotBrain>(
        source->intrinsics(), flowsteer::robot::robot_brain_config(perception, controller), log);
    source->read(frame, 0.1);
    brain->step({frame, {0.3, 0.0}, 0.1, 5.0});
  };
  restart();
  flowsteer::pipeline::StageTimes sum;
  for (auto _ : state) {
    if (source->read(frame, 0.1) != ReadStatus::ok) {
      state.PauseTiming();
      restart();
      source->read(frame, 0.1);
      state.ResumeTiming();
    }
    const flowsteer::base::Command command = brain->step({frame, {0.3, 0.0}, 0.1, 5.0});
    benchmark::DoNotOptimize(command);
    sum += brain->brain().times();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["flow_ms"] = sum.flow / n;
  state.counters["segment_ms"] = sum.segment / n;
  state.counters["features_ms"] = sum.features / n;
  state.counters["control_ms"] = sum.control / n;
}

BENCHMARK(BM_ReplayRead640x480)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReplayReadUndistort640x480)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReplayReadDisFlow640x480)
    ->Arg(cv::DISOpticalFlow::PRESET_ULTRAFAST)
    ->Arg(cv::DISOpticalFlow::PRESET_FAST)
    ->Arg(cv::DISOpticalFlow::PRESET_MEDIUM)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CaptureToCommand640x480)
    ->ArgName("flow")
    ->Arg(static_cast<int>(flowsteer::servo::FlowMethod::dis_fast))
    ->Arg(static_cast<int>(flowsteer::servo::FlowMethod::dis_medium))
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
