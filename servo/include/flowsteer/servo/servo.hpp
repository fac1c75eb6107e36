#pragma once

// The servo core in one include: from a flow field to a command (a_c, ω).
//
//   FlowField flow = ...;                       // flow_field.hpp: raw flow, optional depth
//   derotate(flow, camera_angular_velocity(measured_turn_rate, mount.pitch_rad));
//   mark_ground(flow, mount, speed, {}, ground_mask);          // ground.hpp
//   segment_by_ids(ids, w, h, ground_mask, segmentation);      // segmentation.hpp
//   auto objects = extractor.extract(flow, segmentation);      // features.hpp: g, w, f, τ
//   Controller controller(goal_reaching({}), 1.0, limits);     // control.hpp
//   ControlOutput out = controller.step({objects, goal_bearing}, {speed});
//
// The same controller on features from exact geometry: geometric_features.hpp. Blumberg's
// motion-energy steering, from the image alone: motion_energy.hpp.

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/analytic_scene.hpp"
#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/dynamics.hpp"
#include "flowsteer/servo/features.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/geometric_features.hpp"
#include "flowsteer/servo/ground.hpp"
#include "flowsteer/servo/motion_energy.hpp"
#include "flowsteer/servo/segmentation.hpp"
