#include "flowsteer/sim_camera/camera_noise.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace flowsteer::sim_camera {

namespace {

// SplitMix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators", OOPSLA
// 2014): the state advances by a constant and each output is a bijective mix of it.
std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

std::uint64_t next(std::uint64_t& state) {
  state += 0x9E3779B97F4A7C15ULL;
  return mix(state);
}

}  // namespace

void add_camera_noise(cv::Mat& image, double sigma_levels, std::uint64_t seed) {
  if (image.depth() != CV_8U) {
    throw std::invalid_argument("add_camera_noise: the image is not 8-bit");
  }
  if (!(sigma_levels > 0.0)) {
    return;
  }
  const auto sigma = static_cast<float>(sigma_levels);
  constexpr float kTwoPi = 2.0F * std::numbers::pi_v<float>;
  constexpr float kUnit = 1.0F / 16777216.0F;  // 2^-24: 24 random bits to [0, 1)
  std::uint64_t state = mix(seed);
  const int values = image.cols * image.channels();
  for (int row = 0; row < image.rows; ++row) {
    std::uint8_t* p = image.ptr<std::uint8_t>(row);
    // Box-Muller: one 64-bit draw gives two uniforms, and they two independent normals.
    for (int k = 0; k < values; k += 2) {
      const std::uint64_t bits = next(state);
      const float u1 = static_cast<float>((bits >> 40U) + 1U) * kUnit;  // (0, 1]: log is finite
      const float u2 = static_cast<float>((bits >> 16U) & 0xFFFFFFU) * kUnit;
      const float r = sigma * std::sqrt(-2.0F * std::log(u1));
      p[k] = cv::saturate_cast<std::uint8_t>(static_cast<float>(p[k]) + r * std::cos(kTwoPi * u2));
      if (k + 1 < values) {
        p[k + 1] = cv::saturate_cast<std::uint8_t>(static_cast<float>(p[k + 1]) +
                                                   r * std::sin(kTwoPi * u2));
      }
    }
  }
}

std::uint64_t camera_noise_seed(std::optional<std::size_t> agent, std::int64_t step) {
  const std::uint64_t who =
      agent ? static_cast<std::uint64_t>(*agent) : std::numeric_limits<std::uint64_t>::max();
  return mix(who) ^ static_cast<std::uint64_t>(step);
}

}  // namespace flowsteer::sim_camera
