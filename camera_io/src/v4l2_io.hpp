#pragma once

// What the V4L2 capture and output devices share: ioctls that name their failure, and the
// driver's strings and fourccs as text.

#include <linux/videodev2.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "flowsteer/camera_io/v4l2_device.hpp"

namespace flowsteer::camera_io::v4l2 {

// "YUYV"; a big-endian variant gets "-BE", as v4l2-ctl prints it.
std::string fourcc_text(std::uint32_t fourcc);

// The driver fills these fixed-size char arrays with a NUL-terminated string, but a full one
// has no terminator.
template <std::size_t N>
std::string fixed_text(const std::uint8_t (&chars)[N]) {
  const auto* begin = reinterpret_cast<const char*>(chars);
  return std::string(begin, strnlen(begin, N));
}

// "VIDIOC_S_FMT on /dev/video0 failed: Invalid argument".
std::string errno_message(const std::string& device, const char* what, int error);
[[noreturn]] void throw_errno(const std::string& device, const char* what, int error);

// ioctl, retried when a signal interrupts it. Returns false with errno set on failure.
bool try_ioctl(int fd, unsigned long request, void* arg);
// The same, throwing std::runtime_error (errno_message) on failure.
void checked_ioctl(int fd, unsigned long request, void* arg, const char* name,
                   const std::string& device);

// The driver's MMAP buffer `index` of `type` (VIDIOC_QUERYBUF), mapped: `buffer` is filled in,
// ready to queue, and the mapping is appended to `mappings`. `what` names it in a failed mmap's
// message ("mmap of a capture buffer").
void map_buffer(int fd, v4l2_buf_type type, std::uint32_t index, const std::string& device,
                const char* what, v4l2_buffer& buffer, std::vector<Mapping>& mappings);

}  // namespace flowsteer::camera_io::v4l2
