#pragma once

#include <span>
#include <string>
#include <string_view>

namespace flowsteer::base {

// The values a number the user gives may take: a closed interval, with the unit it is in.
// A value outside (NaN included) is refused where it is read, naming the field.
struct Bound {
  double min;
  double max;
  std::string_view unit;  // "m", "m/s", "s", "px", ...; empty for a pure number

  bool contains(double value) const { return value >= min && value <= max; }
  // "from 0.001 to 1 s"
  std::string describe() const;
  // "must be from 0.001 to 1 s, got 10": the message for a value outside.
  std::string refusal(double value) const;
};

// A field as a file spells it, with its bound. `field` is the path a reader names in its errors
// with every index left out: "agents[].start" covers agents[0].start, agents[7].start, ...
struct FieldBound {
  std::string field;
  Bound bound;
};

// A field path with its indices left out: "agents[3].goals[1]" -> "agents[].goals[]".
std::string without_indices(std::string_view field);

// The bound of `field` (a reader's path, indices allowed) in `table`; std::logic_error when the
// table has no row for it, a reader asking for a field its table forgot.
const Bound& bound_of(std::span<const FieldBound> table, std::string_view field);

// A number as messages show it: up to 10 significant digits (3600000, 0.001, 1e+30).
std::string format_number(double value);

}  // namespace flowsteer::base
