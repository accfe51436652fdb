#pragma once
// The verdict's text (diagnosis internals): the causes named after the first, each with what it
// adds, appended to the verdict once they are named. Not real-time: allocates strings.
#include <string>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// The causes named after the first (d.causes beyond the first, at least one), each with what it
/// adds, appended to d.verdict; shape is the shape cause the others were judged on top of.
void append_also_named(Diagnosis& d, Cause shape, const std::string& unit);

}  // namespace hystbench::compensation::details::diagnosis
