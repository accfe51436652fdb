#pragma once
// Numbers in the diagnosis's text (internals): the evidence lines, the verdict, the notes and
// the reasons a candidate is not named write their figures through these, which follow the
// library's one rule for numbers as text (hystbench/compensation/number_text.hpp).
#include <string>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation::details {

/// `digits` significant digits (%.*g).
inline std::string num(double v, int digits = 3) { return significant(v, digits); }
/// A fraction as a whole percentage, "12 %".
inline std::string percent(double fraction) { return fixed(100.0 * fraction, 0) + " %"; }

}  // namespace hystbench::compensation::details
