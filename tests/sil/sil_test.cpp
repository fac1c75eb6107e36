// flowsteer sil's checks before anything runs (a machine without vivid, a launch file or
// scenario the loop cannot take: each refused with what is wrong, nothing written) and the robot
// process it starts and stops. The loop itself runs in the VM (tests/sil/sil_vm_test.cpp).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "flowsteer/config/scenario_file.hpp"
#include "flowsteer/sil/sil.hpp"
#include "robot_process.hpp"

namespace {

namespace fs = std::filesystem;
using flowsteer::sil::RobotProcess;
using flowsteer::sil::run_sil;
using flowsteer::sil::SilOptions;

constexpr char kOdriveLaunch[] = R"(camera:
  type: v4l2
  horizontal_fov_rad: 1.047
  v4l2: {device: CAMERA, width_px: 160, height_px: 120, pixel_format: YUYV}
drive:
  type: odrive_can
  odrive: {can_interface: vcan0, left: {node_id: 0, direction: 1}, right: {node_id: 1, direction: -1}}
perception: {height_m: 0.35, pitch_deg: 5}
)";

class SilChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / "flowsteer_sil_test" /
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    options_.robot_agent = std::string(1, 'a');  // GCC 12 warns on "a" here (-Wrestrict)
    options_.output_device = "/dev/flowsteer-no-such-output";
    options_.out_dir = dir_ / "out";
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string launch(std::string text,
                     const std::string& camera = "/dev/flowsteer-no-such-camera") {
    text.replace(text.find("CAMERA"), 6, camera);
    const fs::path path = dir_ / "launch.yaml";
    std::ofstream(path) << text;
    return path.string();
  }

  // run_sil's error on the built-in room, which must leave no output folder behind.
  std::string error_of(const SilOptions& options) {
    std::ostringstream log;
    try {
      run_sil(flowsteer::config::builtin_scenario("room"), options, log);
    } catch (const std::exception& e) {
      EXPECT_FALSE(fs::exists(options.out_dir)) << e.what();
      return e.what();
    }
    ADD_FAILURE() << "run_sil did not refuse";
    return "";
  }

  fs::path dir_;
  SilOptions options_;
};

TEST_F(SilChecks, ACameraThatIsNotV4l2IsRefused) {
  const fs::path video = dir_ / "run.mp4";
  options_.launch_file =
      launch("camera: {type: replay, replay: {path: CAMERA}}\nperception: {height_m: 0.35}\n",
             video.string());
  std::ofstream(video) << "x";
  const std::string error = error_of(options_);
  EXPECT_NE(error.find("the loop needs a v4l2 camera"), std::string::npos) << error;
}

TEST_F(SilChecks, ADriveThatIsNotAnOdriveIsRefused) {
  std::string text = kOdriveLaunch;
  text.replace(text.find("drive:"), text.find("perception:") - text.find("drive:"),
               "drive: {type: sim}\n");
  options_.launch_file = launch(text);
  const std::string error = error_of(options_);
  EXPECT_NE(error.find("drive.type odrive_can"), std::string::npos) << error;
}

TEST_F(SilChecks, AnAgentTheScenarioLacksIsRefusedWithItsAgents) {
  options_.launch_file = launch(kOdriveLaunch);
  options_.robot_agent = "robot";
  const std::string error = error_of(options_);
  EXPECT_NE(error.find("no agent named 'robot' (its agents: a, b, c)"), std::string::npos) << error;
}

TEST_F(SilChecks, WithoutVividItSaysWhatTheLoopNeeds) {
  options_.launch_file = launch(kOdriveLaunch);
  const std::string error = error_of(options_);
  EXPECT_NE(error.find("/dev/flowsteer-no-such-camera: cannot open the capture node"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("modprobe vivid"), std::string::npos) << error;
}

TEST(RobotProcessTest, ReportsTheExitStatus) {
  RobotProcess process({"/bin/sh", "-c", "exit 3"});
  std::optional<int> status;
  for (int i = 0; i < 500 && !status; ++i) {
    status = process.poll();
    ::usleep(10000);
  }
  EXPECT_EQ(status, 3);
}

TEST(RobotProcessTest, StopInterruptsAndKillsWhatIgnoresTheInterrupt) {
  RobotProcess polite({"/bin/sleep", "30"});
  EXPECT_EQ(polite.stop(5.0), 128 + SIGINT);
  // exec: the ignored SIGINT carries over to sleep, and no orphan outlives the kill holding the
  // test's output open (ctest waited the 30 s for it).
  RobotProcess stubborn({"/bin/sh", "-c", "trap '' INT; exec sleep 30"});
  ::usleep(200000);  // the shell has set its trap
  EXPECT_EQ(stubborn.stop(0.3), 128 + SIGKILL);
}

}  // namespace
