#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include <opencv2/core.hpp>

namespace flowsteer::sim_camera {

// Adds zero-mean Gaussian noise of standard deviation `sigma_levels` grey levels to each channel
// of each pixel of an 8-bit image, saturating at 0 and 255: the noise a camera's sensor adds.
// The noise is a function of `seed` alone (a counter-based generator, no state shared between
// calls), so that renders on several threads give the same pixels in any order. σ = 0 leaves the
// image as it is. Throws std::invalid_argument for an image that is not 8-bit.
void add_camera_noise(cv::Mat& image, double sigma_levels, std::uint64_t seed);

// The seed of the noise in the view of agent `agent` (none: a view of no agent) at world step
// `step`: another agent or another step, other noise.
std::uint64_t camera_noise_seed(std::optional<std::size_t> agent, std::int64_t step);

}  // namespace flowsteer::sim_camera
