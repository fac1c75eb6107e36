#pragma once

#include <string>

namespace flowsteer::sil {

// Turns vivid's output node into the camera its capture node shows: both switched to their HDMI
// connector with the same timings (CEA 640x480p59.94; vivid scales to and from the frame size,
// up to 4 times), vivid's on-screen text turned off (it would draw counters over the view) and
// its "Loop Video" control on. The capture format is left to the robot process, which sets it as
// it would on a webcam; the output node's format is the V4l2Output's.
//
// Throws std::runtime_error saying what is missing (no such node, not vivid, no HDMI connector,
// a control vivid lacks) with the modprobe line that gives a machine what the loop needs.
// Returns the loop's frame period in seconds: both nodes show and take frames at this rate.
double connect_vivid_loop(const std::string& capture_device, const std::string& output_device);

// The modprobe line `connect_vivid_loop` needs, for error messages and the README.
inline constexpr const char* kVividModprobe =
    "modprobe vivid n_devs=1 node_types=0x101 num_inputs=1 input_types=0x3 num_outputs=1 "
    "output_types=0x1";

}  // namespace flowsteer::sil
