#include "v4l2_io.hpp"

#include "flowsteer/camera_io/v4l2_device.hpp"

#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <stdexcept>

namespace flowsteer::camera_io::v4l2 {

std::string fourcc_text(std::uint32_t fourcc) {
  // Bit 31 marks the big-endian variant of a format (as v4l2-ctl prints it, "-BE").
  const bool big_endian = (fourcc & (1u << 31)) != 0;
  std::string text;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & (i == 3 ? 0x7f : 0xff));
    if (c != ' ') {
      text += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
    }
  }
  return big_endian ? text + "-BE" : text;
}

std::string errno_message(const std::string& device, const char* what, int error) {
  return std::string(what) + " on " + device + " failed: " + std::strerror(error);
}

[[noreturn]] void throw_errno(const std::string& device, const char* what, int error) {
  throw std::runtime_error(errno_message(device, what, error));
}

bool try_ioctl(int fd, unsigned long request, void* arg) {
  int result;
  do {
    result = ::ioctl(fd, request, arg);
  } while (result == -1 && errno == EINTR);
  return result != -1;
}

void checked_ioctl(int fd, unsigned long request, void* arg, const char* name,
                   const std::string& device) {
  if (!try_ioctl(fd, request, arg)) {
    throw_errno(device, name, errno);
  }
}

Mapping::~Mapping() {
  if (data_ != nullptr) {
    ::munmap(data_, length_);
  }
}

std::span<const std::uint8_t> Mapping::bytes(std::size_t bytes_used) const {
  return {static_cast<const std::uint8_t*>(data_), std::min(bytes_used, length_)};
}

void map_buffer(int fd, v4l2_buf_type type, std::uint32_t index, const std::string& device,
                const char* what, v4l2_buffer& buffer, std::vector<Mapping>& mappings) {
  buffer = v4l2_buffer{};
  buffer.type = type;
  buffer.memory = V4L2_MEMORY_MMAP;
  buffer.index = index;
  checked_ioctl(fd, VIDIOC_QUERYBUF, &buffer, "VIDIOC_QUERYBUF", device);
  void* data =
      ::mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, buffer.m.offset);
  if (data == MAP_FAILED) {
    throw_errno(device, what, errno);
  }
  mappings.emplace_back(data, buffer.length);
}

}  // namespace flowsteer::camera_io::v4l2
