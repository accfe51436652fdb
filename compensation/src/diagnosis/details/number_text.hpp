#pragma once
// Numbers in the diagnosis's text (internals): the evidence lines, the verdict, the notes and
// the reasons a candidate is not named write their figures through these.
#include <string>

namespace hystbench::compensation::details {

/// printf-style %.3g / %.4g helpers for evidence lines.
std::string num(double v, int digits = 3);
std::string percent(double fraction);

}  // namespace hystbench::compensation::details
