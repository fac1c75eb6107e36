// The camera's noise: deterministic from its seed, of the σ asked for, on the image alone.
#include "flowsteer/sim_camera/camera_noise.hpp"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "flowsteer/sim_camera/renderer.hpp"

namespace flowsteer::sim_camera {
namespace {

// Bit for bit (a norm would take the sky's infinite depths for a difference).
bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

TEST(CameraNoise, TheSameSeedGivesTheSameImageAndZeroLeavesItAsItIs) {
  const cv::Mat clean(240, 320, CV_8UC3, cv::Scalar(128, 128, 128));
  cv::Mat a = clean.clone();
  cv::Mat b = clean.clone();
  cv::Mat other = clean.clone();
  add_camera_noise(a, 2.0, camera_noise_seed(0, 7));
  add_camera_noise(b, 2.0, camera_noise_seed(0, 7));
  add_camera_noise(other, 2.0, camera_noise_seed(0, 8));
  EXPECT_TRUE(same_pixels(a, b));
  EXPECT_FALSE(same_pixels(a, clean));
  EXPECT_FALSE(same_pixels(a, other));
  cv::Mat untouched = clean.clone();
  add_camera_noise(untouched, 0.0, camera_noise_seed(0, 7));
  EXPECT_TRUE(same_pixels(untouched, clean));
  EXPECT_NE(camera_noise_seed(0, 1), camera_noise_seed(1, 0));
  EXPECT_NE(camera_noise_seed(std::nullopt, 0), camera_noise_seed(0, 0));
}

TEST(CameraNoise, ItsStandardDeviationIsSigmaOnAMidGreyImage) {
  for (const double sigma : {1.0, 2.0, 8.0}) {
    const cv::Mat clean(240, 320, CV_8UC3, cv::Scalar(128, 128, 128));
    cv::Mat noisy = clean.clone();
    add_camera_noise(noisy, sigma, camera_noise_seed(3, 11));
    cv::Mat difference;
    noisy.convertTo(difference, CV_64FC3);
    difference -= cv::Scalar(128, 128, 128);
    cv::Scalar mean;
    cv::Scalar stddev;
    cv::meanStdDev(difference.reshape(1), mean, stddev);
    EXPECT_NEAR(stddev[0], sigma, 0.1 * sigma) << "σ " << sigma;
    EXPECT_NEAR(mean[0], 0.0, 0.02 * sigma) << "σ " << sigma;
  }
}

TEST(CameraNoise, SaturatesAndRefusesImagesThatAreNotEightBit) {
  cv::Mat white(16, 16, CV_8UC1, cv::Scalar(255));
  add_camera_noise(white, 20.0, 1);
  double max_value = 0.0;
  cv::minMaxLoc(white, nullptr, &max_value);
  EXPECT_EQ(max_value, 255.0);
  EXPECT_LT(cv::mean(white)[0], 255.0);
  cv::Mat floats(4, 4, CV_32F, cv::Scalar(0.5));
  EXPECT_THROW(add_camera_noise(floats, 1.0, 1), std::invalid_argument);
}

// The renderer adds the agent's camera noise to the image and to nothing else, the same at the
// same step.
TEST(CameraNoise, TheRendererAddsItToTheImageAlone) {
  WorldSpec spec;
  AgentSpec agent;
  agent.goals = {{10.0, 0.0}};
  agent.camera.width_px = 96;
  agent.camera.height_px = 72;
  spec.agents = {agent};
  Solid wall;
  wall.centre_m = {4.0, 0.0};
  wall.size_m = {0.2, 4.0};
  spec.obstacles = {wall};
  const World clean_world(spec);
  spec.agents[0].camera.noise_sigma_levels = 3.0;
  const World noisy_world(spec);
  std::unique_ptr<Renderer> renderer = Renderer::create();
  RenderedView clean;
  RenderedView noisy;
  RenderedView again;
  renderer->render(clean_world, View::of_agent(clean_world, 0), clean);
  renderer->render(noisy_world, View::of_agent(noisy_world, 0), noisy);
  renderer->render(noisy_world, View::of_agent(noisy_world, 0), again);
  EXPECT_TRUE(same_pixels(noisy.image, again.image));
  EXPECT_FALSE(same_pixels(noisy.image, clean.image));
  EXPECT_TRUE(same_pixels(noisy.depth_m, clean.depth_m));
  EXPECT_TRUE(same_pixels(noisy.object_ids, clean.object_ids));
  EXPECT_TRUE(same_pixels(noisy.flow, clean.flow));
}

}  // namespace
}  // namespace flowsteer::sim_camera
