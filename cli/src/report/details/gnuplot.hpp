#pragma once
// Running gnuplot for the CLI's reports (diagnose --report, sweep --plot). Not real-time.
#include <filesystem>
#include <string>

namespace hystbench::cli::details {

/// Runs `gnuplot script` with its output into log. Throws std::runtime_error naming the cause:
/// gnuplot missing (the script and its data are left for the user), or its error's tail.
void run_gnuplot(const std::filesystem::path& script, const std::filesystem::path& log);

/// A path as a single-quoted gnuplot string.
std::string gnuplot_quoted(const std::filesystem::path& p);

}  // namespace hystbench::cli::details
