#pragma once

// A CAN VM test's console (tests/vm): the probe's "PROBE key value" lines and candump's record
// of the bus (`candump -L`), which the VM's /init prints between "=== CAPTURE BEGIN ===" and
// "=== CAPTURE END ===".

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "vm_test_support.hpp"

namespace flowsteer::vm_test {

struct CanFrame {
  double time_s = 0.0;  // candump's CLOCK_REALTIME stamp
  unsigned id = 0;
  bool rtr = false;
  std::string hex;  // payload as candump prints it, upper case
  // ODrive CAN Simple: the node id in the upper six bits, the command in the lower five.
  unsigned node() const { return id >> 5; }
  unsigned cmd() const { return id & 0x1f; }
  float f32(int index) const {
    std::uint8_t b[4];
    for (int i = 0; i < 4; ++i) {
      b[i] = static_cast<std::uint8_t>(std::stoul(hex.substr(8 * index + 2 * i, 2), nullptr, 16));
    }
    float value;
    std::memcpy(&value, b, 4);
    return value;
  }
  std::string text() const {
    char id_text[8];
    std::snprintf(id_text, sizeof id_text, "%03X", id);
    return std::string(id_text) + "#" + (rtr ? "R" : hex);
  }
};

struct CanCaptureRun {
  std::string console;
  std::map<std::string, std::string> probe;  // "activate" → "1700000000.123456", ...
  std::vector<CanFrame> frames;
};

// "(1700000000.123456) vcan0 06B#0200000001000000" → CanFrame.
inline std::optional<CanFrame> parse_candump(const std::string& line) {
  CanFrame f;
  char iface[32];
  char body[64];
  if (std::sscanf(line.c_str(), " (%lf) %31s %63s", &f.time_s, iface, body) != 3) {
    return std::nullopt;
  }
  const std::string text = body;
  const std::size_t hash = text.find('#');
  if (hash == std::string::npos || hash > 3) {  // standard 11-bit ids only
    return std::nullopt;
  }
  f.id = static_cast<unsigned>(std::stoul(text.substr(0, hash), nullptr, 16));
  const std::string data = text.substr(hash + 1);
  f.rtr = !data.empty() && data[0] == 'R';
  f.hex = f.rtr ? "" : data;
  return f;
}

inline CanCaptureRun parse_can_capture(const std::string& console) {
  CanCaptureRun run;
  run.console = console;
  bool in_capture = false;
  for_each_line(console, [&](const std::string& line) {
    if (line.find("=== CAPTURE BEGIN ===") != std::string::npos) {
      in_capture = true;
    } else if (line.find("=== CAPTURE END ===") != std::string::npos) {
      in_capture = false;
    } else if (in_capture) {
      if (const auto frame = parse_candump(line)) {
        run.frames.push_back(*frame);
      }
    } else if (const auto probe = probe_line(line)) {
      run.probe[probe->key] = probe->value;
    }
  });
  return run;
}

// The number a probe line starts with (a CLOCK_REALTIME stamp); NaN when the key is missing.
inline double stamp(const CanCaptureRun& run, const std::string& key) {
  const auto it = run.probe.find(key);
  return it == run.probe.end() ? NAN : std::atof(it->second.c_str());
}

// Frames the drive sends (not the axes' heartbeats and estimates, not the RTR requests).
inline bool from_drive(const CanFrame& f) {
  return !f.rtr && (f.cmd() == 0x07 || f.cmd() == 0x0b || f.cmd() == 0x0d);
}

inline std::vector<std::string> drive_frames_between(const CanCaptureRun& run, double from_s,
                                                     double to_s) {
  std::vector<std::string> out;
  for (const CanFrame& f : run.frames) {
    if (f.time_s >= from_s && f.time_s <= to_s && from_drive(f)) {
      out.push_back(f.text());
    }
  }
  return out;
}

// ODrive's Set_Input_Vel to `node` (not a request).
inline bool is_set_input_vel(const CanFrame& f, unsigned node) {
  return !f.rtr && f.node() == node && f.cmd() == 0x0d;
}

// The time of the first Set_Input_Vel of zero to `node` after `from_s`.
inline std::optional<double> first_zero_velocity(const CanCaptureRun& run, unsigned node,
                                                 double from_s) {
  for (const CanFrame& f : run.frames) {
    if (f.time_s > from_s && is_set_input_vel(f, node) && f.f32(0) == 0.0f) {
      return f.time_s;
    }
  }
  return std::nullopt;
}

// How many non-zero velocities `node` was sent in (from_s, to_s].
inline int times_driven(const CanCaptureRun& run, unsigned node, double from_s, double to_s) {
  int count = 0;
  for (const CanFrame& f : run.frames) {
    count += f.time_s > from_s && f.time_s <= to_s && is_set_input_vel(f, node) && f.f32(0) != 0.0f;
  }
  return count;
}

// Whether `node` was sent a non-zero velocity in (from_s, to_s].
inline bool driven(const CanCaptureRun& run, unsigned node, double from_s, double to_s) {
  return times_driven(run, node, from_s, to_s) > 0;
}

// The longest time between two consecutive Set_Input_Vel to `node` in (from_s, to_s]: `flowsteer
// run` sends one per pass of its loop, so this is its slowest pass (a frame's perception and the
// wait for the next frame); 0 with fewer than two.
inline double longest_command_gap_s(const CanCaptureRun& run, unsigned node, double from_s,
                                    double to_s) {
  double longest_s = 0.0;
  double last_s = NAN;
  for (const CanFrame& f : run.frames) {
    if (f.time_s > from_s && f.time_s <= to_s && is_set_input_vel(f, node)) {
      longest_s = std::isnan(last_s) ? longest_s : std::max(longest_s, f.time_s - last_s);
      last_s = f.time_s;
    }
  }
  return longest_s;
}

// The time a stop (or the report that none can be sent) may take after a fault that came while
// `flowsteer run` drove between from_s and fault_s: the pass the fault interrupts ends first. On
// a robot's computer a pass is a few tens of ms and this is `floor_s`; on the VM's emulated CPU
// a pass takes 0.3-0.8 s, more on a loaded host, so it is the slowest pass seen before the fault
// and half of that again for the one the fault came in.
inline double stop_bound_s(const CanCaptureRun& run, std::span<const unsigned> nodes, double from_s,
                           double fault_s, double floor_s) {
  double slowest_pass_s = 0.0;
  for (const unsigned node : nodes) {
    slowest_pass_s = std::max(slowest_pass_s, longest_command_gap_s(run, node, from_s, fault_s));
  }
  return std::max(floor_s, 1.5 * slowest_pass_s);
}

}  // namespace flowsteer::vm_test
