#include "flowsteer/servo/optical_flow.hpp"

#include <array>
#include <stdexcept>
#include <string>

#include "image_flow.hpp"
#include "renderer_flow.hpp"

namespace flowsteer::servo {

namespace {

constexpr std::array kNumericalMethods{FlowMethod::dis_ultrafast, FlowMethod::dis_fast,
                                       FlowMethod::dis_medium, FlowMethod::farneback,
                                       FlowMethod::tvl1};

}  // namespace

std::string_view to_string(FlowMethod method) {
  switch (method) {
    case FlowMethod::synthetic:
      return "synthetic";
    case FlowMethod::dis_ultrafast:
      return "dis_ultrafast";
    case FlowMethod::dis_fast:
      return "dis_fast";
    case FlowMethod::dis_medium:
      return "dis_medium";
    case FlowMethod::farneback:
      return "farneback";
    case FlowMethod::tvl1:
      return "tvl1";
  }
  return "unknown";
}

std::optional<FlowMethod> parse_flow_method(std::string_view name) {
  if (name == to_string(FlowMethod::synthetic))
    return FlowMethod::synthetic;
  for (FlowMethod method : kNumericalMethods) {
    if (name == to_string(method))
      return method;
  }
  return std::nullopt;
}

std::string flow_method_names() {
  std::string names(to_string(FlowMethod::synthetic));
  for (FlowMethod method : kNumericalMethods) {
    names += ", ";
    names += to_string(method);
  }
  return names;
}

std::span<const FlowMethod> numerical_flow_methods() {
  return kNumericalMethods;
}

const char* to_string(FlowStatus status) {
  switch (status) {
    case FlowStatus::ok:
      return "ok";
    case FlowStatus::no_previous_frame:
      return "no previous frame";
    case FlowStatus::size_changed:
      return "image size changed";
    case FlowStatus::empty_frame:
      return "empty frame";
    case FlowStatus::untextured:
      return "single-colour frame";
    case FlowStatus::no_time_elapsed:
      return "timestamp did not increase";
    case FlowStatus::time_went_back:
      return "timestamp went back";
  }
  return "unknown";
}

std::unique_ptr<FlowSource> make_flow_source(FlowMethod method, const OpticalFlowOptions& estimator,
                                             const RendererFlowOptions& renderer) {
  switch (method) {
    case FlowMethod::synthetic:
      return std::make_unique<RendererFlow>(renderer);
    case FlowMethod::dis_ultrafast:
      return std::make_unique<DisFlow>(cv::DISOpticalFlow::PRESET_ULTRAFAST, estimator);
    case FlowMethod::dis_fast:
      return std::make_unique<DisFlow>(cv::DISOpticalFlow::PRESET_FAST, estimator);
    case FlowMethod::dis_medium:
      return std::make_unique<DisFlow>(cv::DISOpticalFlow::PRESET_MEDIUM, estimator);
    case FlowMethod::farneback:
      return std::make_unique<FarnebackFlow>(estimator);
    case FlowMethod::tvl1:
      return std::make_unique<TvL1Flow>(estimator);
  }
  throw std::invalid_argument("make_flow_source: not a FlowMethod");
}

}  // namespace flowsteer::servo
