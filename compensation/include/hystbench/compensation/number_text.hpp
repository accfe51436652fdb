#pragma once
// Numbers as text for messages, labels and notes, one rule for every library: printf's %g and %f
// rounding (correctly rounded), "nan", "-nan", "inf" and "-inf" for the values that are not
// finite. Allocates: not for the real-time path.
#include <string>

namespace hystbench::compensation {

/// v to `digits` significant digits, trailing zeros dropped, as printf's %.*g: 12.5, 0.000125,
/// 1.25e+06 (digits >= 1).
std::string significant(double v, int digits);

/// v with `digits` decimals, as printf's %.*f: 12.500, -0.125, 1250000.000 (digits >= 0).
std::string fixed(double v, int digits);

/// A fraction as a percentage to `digits` significant digits, with its sign: 0.125 -> "12.5 %".
std::string percent(double fraction, int digits);

/// The shortest text that reads back to the same double: 0.1, 20000, 1e-05, 1e+16.
std::string shortest(double v);

}  // namespace hystbench::compensation
