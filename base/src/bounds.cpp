#include "flowsteer/base/bounds.hpp"

#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace flowsteer::base {

std::string format_number(double value) {
  std::ostringstream s;
  s << std::setprecision(10) << value;
  return s.str();
}

std::string Bound::describe() const {
  std::ostringstream s;
  s << std::setprecision(10) << "from " << min << " to " << max;
  if (!unit.empty()) {
    s << " " << unit;
  }
  return s.str();
}

std::string Bound::refusal(double value) const {
  return "must be " + describe() + ", got " + format_number(value);
}

std::string without_indices(std::string_view field) {
  std::string out;
  bool in_index = false;
  for (const char c : field) {
    if (c == '[') {
      in_index = true;
      out += c;
    } else if (c == ']') {
      in_index = false;
      out += c;
    } else if (!in_index) {
      out += c;
    }
  }
  return out;
}

const Bound& bound_of(std::span<const FieldBound> table, std::string_view field) {
  const std::string key = without_indices(field);
  for (const FieldBound& row : table) {
    if (row.field == key) {
      return row.bound;
    }
  }
  throw std::logic_error("no bound for the field '" + key + "' in its reader's table");
}

}  // namespace flowsteer::base
