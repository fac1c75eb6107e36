#include "vivid_loop.hpp"

#include <fcntl.h>
#include <linux/v4l2-dv-timings.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "flowsteer/base/unique_fd.hpp"

namespace flowsteer::sil {

namespace {

// A device node opened for the setup only.
class Node {
 public:
  Node(const std::string& path, std::uint32_t needed_cap, const char* role) : path_(path) {
    fd_ = base::UniqueFd(::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC));
    if (!fd_) {
      fail(std::string("cannot open the ") + role + " node: " + std::strerror(errno));
    }
    v4l2_capability cap{};
    if (::ioctl(fd_.get(), VIDIOC_QUERYCAP, &cap) != 0) {
      fail(std::string("VIDIOC_QUERYCAP failed: ") + std::strerror(errno));
    }
    const auto* driver = reinterpret_cast<const char*>(cap.driver);
    if (std::strncmp(driver, "vivid", sizeof cap.driver) != 0) {
      fail(std::string("its driver is ") + driver + ", not vivid");
    }
    if ((cap.device_caps & needed_cap) == 0) {
      fail(std::string("not vivid's ") + role + " node");
    }
  }

  // ioctl that throws naming the node and the request.
  void control(unsigned long request, void* arg, const char* name) const {
    if (::ioctl(fd_.get(), request, arg) != 0) {
      fail(std::string(name) + " failed: " + std::strerror(errno));
    }
  }
  bool try_control(unsigned long request, void* arg) const {
    return ::ioctl(fd_.get(), request, arg) == 0;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("vivid loop: " + path_ + ": " + what + " (the loop needs `" +
                             kVividModprobe + "`; see docs/COMMANDS.md, \"flowsteer sil\")");
  }

  // Sets vivid's control `name` (vivid's own controls have ids in no header).
  void set_control(const char* name, std::int32_t value) const {
    v4l2_queryctrl query{};
    query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
    while (try_control(VIDIOC_QUERYCTRL, &query)) {
      if (std::strcmp(reinterpret_cast<const char*>(query.name), name) == 0) {
        v4l2_control set{query.id, value};
        control(VIDIOC_S_CTRL, &set, name);
        return;
      }
      query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
    }
    fail(std::string("vivid has no control \"") + name + "\" here");
  }

 private:
  std::string path_;
  base::UniqueFd fd_;
};

void select_hdmi_input(const Node& capture) {
  for (v4l2_input input{}; capture.try_control(VIDIOC_ENUMINPUT, &input); ++input.index) {
    if ((input.capabilities & V4L2_IN_CAP_DV_TIMINGS) != 0) {
      int index = static_cast<int>(input.index);
      capture.control(VIDIOC_S_INPUT, &index, "VIDIOC_S_INPUT");
      return;
    }
  }
  capture.fail("no HDMI input (vivid's input_types: 3 for HDMI)");
}

void select_hdmi_output(const Node& output) {
  for (v4l2_output out{}; output.try_control(VIDIOC_ENUMOUTPUT, &out); ++out.index) {
    if ((out.capabilities & V4L2_OUT_CAP_DV_TIMINGS) != 0) {
      int index = static_cast<int>(out.index);
      output.control(VIDIOC_S_OUTPUT, &index, "VIDIOC_S_OUTPUT");
      return;
    }
  }
  output.fail("no HDMI output (vivid's output_types: 1 for HDMI)");
}

}  // namespace

double connect_vivid_loop(const std::string& capture_device, const std::string& output_device) {
  const Node capture(capture_device, V4L2_CAP_VIDEO_CAPTURE, "capture");
  const Node output(output_device, V4L2_CAP_VIDEO_OUTPUT, "output");
  select_hdmi_input(capture);
  select_hdmi_output(output);
  v4l2_dv_timings timings = V4L2_DV_BT_CEA_640X480P59_94;
  capture.control(VIDIOC_S_DV_TIMINGS, &timings, "VIDIOC_S_DV_TIMINGS");
  timings = V4L2_DV_BT_CEA_640X480P59_94;
  output.control(VIDIOC_S_DV_TIMINGS, &timings, "VIDIOC_S_DV_TIMINGS");
  capture.set_control("OSD Text Mode", 2);  // 2: none
  capture.set_control("Loop Video", 1);
  const v4l2_bt_timings& bt = timings.bt;
  return static_cast<double>(V4L2_DV_BT_FRAME_WIDTH(&bt)) * V4L2_DV_BT_FRAME_HEIGHT(&bt) /
         static_cast<double>(bt.pixelclock);
}

}  // namespace flowsteer::sil
