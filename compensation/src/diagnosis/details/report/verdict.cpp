#include "diagnosis/details/report/verdict.hpp"

#include "diagnosis/details/naming/decision.hpp"
#include "diagnosis/details/number_text.hpp"

namespace hystbench::compensation::details::diagnosis {

void append_also_named(Diagnosis& d, Cause shape, const std::string& unit) {
  d.verdict += ". Also named, each adding more than the noise allows (" +
               num(d.noise_allowance_rms) + " " + unit + " rms) to the causes before it: ";
  for (std::size_t i = 1; i < d.causes.size(); ++i) {
    const NamedCause& n = d.causes[i];
    // The shape, last, is judged on top of the first cause alone.
    const std::string to = is_shape(n.cause) && i > 1
                               ? std::string(to_string(d.causes.front().cause))
                               : std::string("those");
    d.verdict += (i > 1 ? ", " : "") + std::string(to_string(n.cause)) + " (gain " + num(n.gain) +
                 (n.against == shape_name(shape) ? " over the shape" : "") + ", " +
                 num(n.added_gain) + " added to ";
    d.verdict += to;
    d.verdict += ", " + num(n.added_rms) + " " + unit + " rms)";
  }
}

}  // namespace hystbench::compensation::details::diagnosis
