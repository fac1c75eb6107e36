#pragma once

// One table per file format naming every bounded field with the bound of its quantity
// (base/quantity_bounds.hpp; `flowsteer bounds` prints them, docs/INPUT_BOUNDS.md explains them).
// Readers take a field's bound from its table; tests walk the tables, every field just inside and
// just outside each end.

#include <span>

#include "flowsteer/base/bounds.hpp"

namespace flowsteer::config {

// One row per bounded field of each format, as its reader names the field.
std::span<const base::FieldBound> scenario_bounds();      // scenario YAML
std::span<const base::FieldBound> robot_launch_bounds();  // robot launch YAML
std::span<const base::FieldBound> demo_scene_bounds();    // demo scene YAML
// SteerSuite XML: "parent/element", e.g. "initialConditions/radius", "position/x".
std::span<const base::FieldBound> steersuite_bounds();

}  // namespace flowsteer::config
