#pragma once
// Progress of a diagnosis (internals): the options' callback, told how far the diagnosis is and
// what it does. Called between stages, never inside a fit; one at a time where the candidates run
// side by side.
#include <string>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

// Calls the options' progress callback, when there is one.
inline void report(const DiagnosisOptions& options, double fraction, const std::string& what) {
  if (options.progress) options.progress(fraction, what);
}

}  // namespace hystbench::compensation::details::diagnosis
