// Runs inside the test VM (tests/vm/run_can_vm.sh): a simulated pair of ODrive axes and the
// ODrive CAN drive behind a MobileBase on vcan0, through activate, a velocity stream, commands that
// cease (the watchdog must stop the wheels), deactivate, an axis error and a lost heartbeat. It
// prints what it did as "PROBE key value" lines with CLOCK_REALTIME stamps, the clock candump
// stamps frames with; the host test checks those against candump's capture of the bus.

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/drivers/mobile_base.hpp"
#include "flowsteer/drivers/odrive_can.hpp"
#include "flowsteer/drivers/simulated_odrive.hpp"
#include "probe_support.hpp"

namespace {

using namespace flowsteer::drivers;
using flowsteer::base::monotonic_now_s;
using flowsteer::vm_test::realtime_s;

constexpr double kLoopPeriodS = 0.02;
constexpr std::uint8_t kLeftNode = 3;
constexpr std::uint8_t kRightNode = 5;

// Calls update() every loop period for duration_s; `command` says whether to send a fresh
// command first. Returns the realtime of the last command sent; `commanded` gets the state
// the last update after a command returned; `update_starts` gets the realtime at which each
// update() began.
template <typename Command>
double run_loop(MobileBase& base, double duration_s, Command command,
                BaseState* commanded = nullptr, std::vector<double>* update_starts = nullptr) {
  double last_command_realtime_s = 0.0;
  const double start_s = monotonic_now_s();
  for (double next_s = start_s; monotonic_now_s() - start_s < duration_s; next_s += kLoopPeriodS) {
    std::this_thread::sleep_for(std::chrono::duration<double>(next_s - monotonic_now_s()));
    const bool fresh = command(monotonic_now_s() - start_s);
    if (fresh) {
      base.command({5.0, 0.6}, monotonic_now_s());
      last_command_realtime_s = realtime_s();
    }
    if (update_starts != nullptr) {
      update_starts->push_back(realtime_s());
    }
    const BaseState state = base.update(monotonic_now_s());
    if (fresh && commanded != nullptr) {
      *commanded = state;
    }
  }
  return last_command_realtime_s;
}

// Prints when each update() of a loop began, under `key`-updates.
void print_update_starts(const char* key, const std::vector<double>& update_starts) {
  std::printf("PROBE %s-updates", key);
  for (const double start_s : update_starts) {
    std::printf(" %.6f", start_s);
  }
  std::printf("\n");
}

// Drives for 2 s, calling inject() from 0.3 s on, and prints how the base failed under `key`
// and when each update() began under `key`-updates (the last is the one that failed).
template <typename Inject>
void drive_into_fault(MobileBase& base, const char* key, Inject inject) {
  std::vector<double> update_starts;
  update_starts.reserve(static_cast<std::size_t>(2.0 / kLoopPeriodS) + 2);
  try {
    run_loop(
        base, 2.0,
        [&](double t_s) {
          if (t_s > 0.3) {
            inject();
          }
          return true;
        },
        nullptr, &update_starts);
    std::printf("PROBE %s no error\n", key);
  } catch (const DriveError& e) {
    std::printf("PROBE %s %.6f %s\n", key, realtime_s(), e.what());
  }
  print_update_starts(key, update_starts);
}

int run() {
  OdriveCanConfig drive_config;
  drive_config.interface = "vcan0";
  drive_config.left = {kLeftNode, 1.0};
  drive_config.right = {kRightNode, -1.0};
  drive_config.timeout_s = 0.3;

  // A missing interface: a clear error, quickly.
  {
    OdriveCanConfig missing = drive_config;
    missing.interface = "vcan7";
    OdriveCanDrive drive(missing);
    try {
      drive.configure();
      std::printf("PROBE missing-interface no error\n");
    } catch (const DriveError& e) {
      std::printf("PROBE missing-interface %s\n", e.what());
    }
  }

  flowsteer::drivers::SimulatedOdrive axes("vcan0", kLeftNode, kRightNode);
  CommandStageConfig stage;
  stage.geometry = {0.4, 0.05};
  stage.limits.max_speed_mps = 0.5;
  stage.limits.max_accel_mps2 = 5.0;
  stage.limits.max_turn_rate = 1.0;
  stage.watchdog = {0.3, 0.1};
  MobileBase base(std::make_unique<OdriveCanDrive>(drive_config), stage);

  base.configure();
  std::printf("PROBE activate %.6f\n", realtime_s());
  base.activate(monotonic_now_s());
  std::printf("PROBE stream %.6f\n", realtime_s());
  // Commands for 1 s, then none for 0.6 s while the loop goes on.
  BaseState commanded;
  std::vector<double> update_starts;
  update_starts.reserve(static_cast<std::size_t>(1.6 / kLoopPeriodS) + 2);
  const double last_command_s = run_loop(
      base, 1.6, [](double t_s) { return t_s < 1.0; }, &commanded, &update_starts);
  std::printf("PROBE last-command %.6f\n", last_command_s);
  print_update_starts("stream", update_starts);
  // What the drive measured from the simulated axes' encoder estimates while commanded.
  std::printf("PROBE measured %.6f %.6f %.6f %.6f %zu\n", commanded.measured.speed_mps,
              commanded.measured.turn_rate, commanded.drive.odometry.left_rad,
              commanded.drive.odometry.right_rad, commanded.drive.faults.size());
  std::printf("PROBE deactivate %.6f\n", realtime_s());
  base.deactivate();
  std::printf("PROBE deactivated %.6f\n", realtime_s());

  // An axis error while driving: the base stops and says which axis and what.
  base.activate(monotonic_now_s());
  drive_into_fault(base, "axis-error", [&] { axes.fail_axis(kRightNode); });

  // A heartbeat lost while driving: the base stops both axes and names the silent one.
  std::printf("PROBE heartbeat-lost-start %.6f\n", realtime_s());
  axes.fail_axis(std::nullopt);
  base.configure();
  base.activate(monotonic_now_s());
  drive_into_fault(base, "heartbeat-lost", [&] { axes.silence_axis(kLeftNode); });
  std::printf("PROBE done\n");
  return 0;
}

}  // namespace

int main() {
  return flowsteer::vm_test::probe_main(run);
}
