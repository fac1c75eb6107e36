#pragma once

// What each number a user gives may be: the physical or engineering bounds of each quantity, with
// its unit. The readers' tables (config/field_bounds.hpp) give each field of a file one of these;
// the command line's options and the calibration files' readers take them directly
// (docs/INPUT_BOUNDS.md).

#include <numbers>

#include "flowsteer/base/bounds.hpp"

namespace flowsteer::base::bounds {

// The simulator: a control period from 1 ms to 1 s, a run of at most an hour, so at most
// kMaxRunSteps steps.
inline constexpr Bound kStep_s{0.001, 1.0, "s"};
inline constexpr Bound kDuration_s{0.001, 3600.0, "s"};
inline constexpr int kMaxRunSteps = 3'600'000;  // kDuration_s.max / kStep_s.min
inline constexpr Bound kRunSteps{1, kMaxRunSteps, "steps"};
// A recording's camera images: every Nth frame (0: none), at least one a minute at 30 Hz.
inline constexpr Bound kImagesEvery_frames{0, 1800, "frames"};

// Where things are: a world within a kilometre of its origin (float geometry keeps millimetres
// there), and how big they are.
inline constexpr Bound kPosition_m{-1000.0, 1000.0, "m"};
inline constexpr Bound kGroundSize_m{1.0, 10000.0, "m"};
inline constexpr Bound kExtent_m{0.001, 3000.0, "m"};     // a box's side, a wall's length
inline constexpr Bound kObjectSize_m{0.001, 100.0, "m"};  // a radius, a thickness, a car
inline constexpr Bound kObstacleHeight_m{0.01, 200.0, "m"};
// SteerSuite's up axis: an elevation and a height (0 for flat), so that a top is within 200 m.
inline constexpr Bound kElevation_m{-100.0, 100.0, "m"};
inline constexpr Bound kHeightSpan_m{0.0, 100.0, "m"};
inline constexpr Bound kAngle_deg{-360.0, 360.0, "deg"};
inline constexpr Bound kTimeDuration_s{0.0, 1e6, "s"};  // SteerSuite's <timeDuration>

// A person or a wheeled robot: bodies, speeds, accelerations and turn rates they can have.
inline constexpr Bound kBodyRadius_m{0.05, 2.0, "m"};
inline constexpr Bound kBodyHeight_m{0.05, 5.0, "m"};
inline constexpr Bound kGoalRadius_m{0.01, 10.0, "m"};
inline constexpr Bound kSpeed_mps{0.0, 10.0, "m/s"};           // a sprint
inline constexpr Bound kPreferredSpeed_mps{0.01, 6.0, "m/s"};  // walking to running
inline constexpr Bound kMaxSpeed_mps{0.01, 10.0, "m/s"};
inline constexpr Bound kAccel_mps2{0.01, 20.0, "m/s^2"};
inline constexpr Bound kTurnRate_radps{0.01, 10.0, "rad/s"};
inline constexpr Bound kSignedTurnRate_radps{-10.0, 10.0, "rad/s"};
inline constexpr Bound kVelocity_mps{-50.0, 50.0, "m/s"};  // a component; a car in town
inline constexpr Bound kBodyWidth_m{0.05, 5.0, "m"};

// A camera and the light it sees by.
inline constexpr Bound kImageSide_px{8, 4096, "px"};
inline constexpr Bound kHfov_deg{1.0, 179.0, "deg"};
inline constexpr Bound kHfov_rad{0.02, 3.12, "rad"};  // about 1 to 179 deg
inline constexpr Bound kCameraHeight_m{0.01, 10.0, "m"};
inline constexpr Bound kCameraPitch_deg{-89.0, 89.0, "deg"};
inline constexpr Bound kCameraPitch_rad{-89.0 * std::numbers::pi / 180.0,
                                        89.0 * std::numbers::pi / 180.0, "rad"};  // a mount file's
// Beyond 50 grey levels of σ the image is more noise than picture.
inline constexpr Bound kCameraNoise_levels{0.0, 50.0, "grey levels"};
inline constexpr Bound kLightIntensity{0.0, 10.0, ""};
inline constexpr Bound kLightRange_m{0.01, 2000.0, "m"};
inline constexpr Bound kLightHeight_m{0.0, 100.0, "m"};
inline constexpr Bound kSunElevation_deg{1.0, 89.0, "deg"};
inline constexpr Bound kCarriedAhead_m{-10.0, 10.0, "m"};
inline constexpr Bound kFraction{0.0, 1.0, ""};  // albedo, contrast, flow_weight
inline constexpr Bound kPositiveFraction{0.001, 1.0, ""};
inline constexpr Bound kPatternScale_m{0.001, 100.0, "m"};

// The controller: cost weights and gains of order one (the papers' are 0.1 to 2), distances of a
// scene.
inline constexpr Bound kCostWeight{0.0, 100.0, ""};
inline constexpr Bound kGain{0.001, 100.0, ""};
inline constexpr Bound kSpeedRatio{1.0, 10.0, ""};
inline constexpr Bound kMargin_m{0.0, 10.0, "m"};
inline constexpr Bound kRange_m{0.01, 1000.0, "m"};

// A robot near people: limits a small wheeled base can plausibly need; a command stage set
// beyond them is refused, not obeyed.
inline constexpr Bound kRobotSpeed_mps{0.01, 3.0, "m/s"};
inline constexpr Bound kRobotReverseSpeed_mps{0.0, 3.0, "m/s"};
inline constexpr Bound kRobotPreferredSpeed_mps{0.0, 3.0, "m/s"};
inline constexpr Bound kRobotAccel_mps2{0.01, 10.0, "m/s^2"};
inline constexpr Bound kRobotTurnRate_radps{0.01, 10.0, "rad/s"};
inline constexpr Bound kWheelSpeed_radps{0.1, 500.0, "rad/s"};
inline constexpr Bound kWheelSeparation_m{0.05, 5.0, "m"};
inline constexpr Bound kWheelRadius_m{0.005, 1.0, "m"};
// The watchdog stops the wheels at most 2 s after the last command, however the file sets it (the
// SIL test's emulated CPU, loaded, stretches it to about 1.1 s: tests/vm/README.md).
inline constexpr Bound kWatchdogTimeout_s{0.02, 2.0, "s"};
inline constexpr Bound kWatchdogRamp_s{0.0, 2.0, "s"};
inline constexpr Bound kLoopRate_hz{2.0, 1000.0, "Hz"};
inline constexpr Bound kFrameRate_hz{0.0, 1000.0, "Hz"};  // 0: the device's own
inline constexpr Bound kBufferCount{2, 32, "buffers"};
inline constexpr Bound kCameraTimeout_s{0.01, 5.0, "s"};
inline constexpr Bound kDeviceTimeout_s{0.001, 2.0, "s"};  // a serial reply, a CAN heartbeat
inline constexpr Bound kBoardTimeout_s{0.1, 25.5, "s"};    // RoboClaw's own serial timeout
inline constexpr Bound kBootWait_s{0.0, 30.0, "s"};
inline constexpr Bound kWheelTimeConstant_s{0.0, 10.0, "s"};
inline constexpr Bound kGearRatio{0.01, 1000.0, ""};
inline constexpr Bound kEncoderTicks{1.0, 1e7, "ticks"};
inline constexpr Bound kPidRate_hz{1.0, 1000.0, "Hz"};
inline constexpr Bound kBaud{300, 4'000'000, "baud"};
inline constexpr Bound kCanNodeId{0, 63, ""};           // 6 bits of the CAN id
inline constexpr Bound kRoboClawAddress{128, 135, ""};  // 0x80 .. 0x87
inline constexpr Bound kDomainId{0, 232, ""};  // ROS 2's DDS domains (ros2_dds::kMaxDomainId)
// DDS discovery on one host takes a fraction of a second; a robot on Wi-Fi may take seconds.
inline constexpr Bound kConnectTimeout_s{0.1, 60.0, "s"};
inline constexpr Bound kBearing_rad{-std::numbers::pi, std::numbers::pi, "rad"};
inline constexpr Bound kBearing_deg{-180.0, 180.0, "deg"};
inline constexpr Bound kGoalDistance_m{0.01, 1000.0, "m"};

}  // namespace flowsteer::base::bounds
