#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>

#include "flowsteer/base/unique_fd.hpp"

namespace flowsteer::camera_io::v4l2 {

// One mmap'ed driver buffer, unmapped when destroyed.
class Mapping {
 public:
  Mapping(void* data, std::size_t length) : data_(data), length_(length) {}
  ~Mapping();
  Mapping(Mapping&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), length_(other.length_) {}
  Mapping& operator=(Mapping&&) = delete;
  // The first bytes_used bytes, clamped to the mapping.
  std::span<const std::uint8_t> bytes(std::size_t bytes_used) const;
  std::span<std::uint8_t> writable() const { return {static_cast<std::uint8_t*>(data_), length_}; }

 private:
  void* data_;
  std::size_t length_;
};

}  // namespace flowsteer::camera_io::v4l2
