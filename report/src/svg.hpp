#pragma once

#include <string>

#include "flowsteer/report/page.hpp"

namespace flowsteer::report {

// Text safe inside HTML and SVG, in elements and in attributes in double quotes (the only
// quotes the pages use).
std::string escaped(const std::string& text);
std::string css_color(const Rgb& color);

// The plot as an inline <svg class="plot">: axes with ticks at round values, a line per series,
// the marks as dashed vertical lines, and a legend where there are few enough series to name.
std::string svg_of(const Plot& plot);

// Each series reduced to the samples svg_of draws of it, so that a page holding the plots of a
// long crowded run holds no more than it draws.
void thin(Plot& plot);

}  // namespace flowsteer::report
