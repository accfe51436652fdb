#pragma once
// The start of a record whose hysteresis state the record itself does not determine (details
// shared by identification and diagnosis). Not real-time: reads the whole input once.
#include <cstddef>
#include <span>

namespace hystbench::compensation::details {

/// Samples at the start of u until the input has come within 0.5 % of its span to both its
/// minimum and its maximum (a PI's memory of what came before is then wiped out), at most
/// max_samples (and at most u's length).
std::size_t startup_samples(std::span<const double> u, std::size_t max_samples);

}  // namespace hystbench::compensation::details
