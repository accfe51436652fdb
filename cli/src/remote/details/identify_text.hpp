#pragma once
// identify's result in words, for the CLI's report of a run (print_run_result): the model it
// chose, its verification on the bench, the rate law, the extension and the other candidates.
// Not real-time.
#include <nlohmann/json.hpp>
#include <ostream>

namespace hystbench::cli::details {

/// The result's `model` (structure, file, fit and held-out errors, the fit's notes), its
/// `verification` through the inverse, whether the rate law was kept, the extension with its
/// parts and the decision, and each of the other `candidates`; nothing for what the result lacks.
void print_identification(std::ostream& out, const nlohmann::json& result);

}  // namespace hystbench::cli::details
