#pragma once
// The feedback's design and the stage's measured frequency responses in words, for the CLI's
// reports of identify, frf, track and tune. Not real-time.
#include <nlohmann/json.hpp>
#include <ostream>

namespace hystbench::cli::details {

/// A result's or tune's `feedback`: the law, the crossover and bandwidths, the margins on the
/// responses against the targets, and what limited it (or which target hand gains break).
void print_feedback(std::ostream& out, const nlohmann::json& feedback);

/// A result's `frequency_response`: the responses' band and gain, their coherence and noise,
/// the modes found, and how far they moved since the responses before.
void print_frequency_response(std::ostream& out, const nlohmann::json& summary);

}  // namespace hystbench::cli::details
