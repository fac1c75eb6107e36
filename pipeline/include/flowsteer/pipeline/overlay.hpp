#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <span>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/features.hpp"
#include "flowsteer/servo/flow_field.hpp"

namespace flowsteer::pipeline {

// An image (a simulated agent's view, a robot's camera, a recording) beside its colour-coded
// derotated flow, with the features drawn on the image: FOE (blue), centre (orange) and TTC of
// each object, the goal's bearing (pink) (CGF Fig. 3). Both halves are enlarged by
// overlay_scale, pixel by pixel, before the features are drawn, so that the overlay is at least
// 640 px wide and its text legible; its size is overlay_size(image.size()).
cv::Mat draw_overlay(const cv::Mat& image, const servo::FlowField& flow,
                     std::span<const servo::ObjectFeatures> objects,
                     const base::CameraIntrinsics& intrinsics,
                     std::optional<double> goal_bearing_rad);
// The whole factor an image is enlarged by in its overlay: 1 for one 320 px wide or more.
int overlay_scale(cv::Size image);
cv::Size overlay_size(cv::Size image);

// Flow as colour: hue for the direction, brightness for the magnitude (up to max_magnitude).
cv::Mat flow_to_color(const servo::FlowField& flow, double max_magnitude);

// Throws std::runtime_error naming the file when OpenCV cannot encode MP4 there.
std::unique_ptr<cv::VideoWriter> open_video(const std::filesystem::path& path, cv::Size size,
                                            double fps);

}  // namespace flowsteer::pipeline
