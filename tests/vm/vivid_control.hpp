#pragma once

// Sets a control of the vivid driver by its name (its private control ids are in no header),
// for the VM probes (tests/vm); prints "PROBE control NAME=VALUE set|failed|not found".

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

namespace flowsteer::vm_test {

// Returns whether the control was set. The device is opened for the call only: vivid brings a
// node back after a "Disconnect" once its last file handle is closed.
inline bool set_vivid_control(const std::string& device, const char* name, std::int32_t value) {
  const int fd = ::open(device.c_str(), O_RDWR | O_NONBLOCK);
  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (fd >= 0 && ::ioctl(fd, VIDIOC_QUERYCTRL, &query) == 0) {
    if (std::strcmp(reinterpret_cast<const char*>(query.name), name) == 0) {
      v4l2_control control{query.id, value};
      const bool set = ::ioctl(fd, VIDIOC_S_CTRL, &control) == 0;
      std::printf("PROBE control %s=%d %s\n", name, value, set ? "set" : "failed");
      ::close(fd);
      return set;
    }
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  std::printf("PROBE control %s not found\n", name);
  if (fd >= 0) {
    ::close(fd);
  }
  return false;
}

}  // namespace flowsteer::vm_test
