#pragma once
// A run's sample log (SampleLogWriter's CSV), decimated for a plot in the page: at most
// `points` rows, evenly spaced, each axis's yr, y and u. Reads the file twice (counts, then
// keeps every k-th row); memory stays O(points). Not real-time safe.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hystbench::daemon::details {

/// Logs larger than this are not plotted in the page (about 35 min of one axis at 10 kHz).
inline constexpr std::uintmax_t kMaxPlottedLogBytes = std::uintmax_t{1} << 30;

/// {"run_id", "rows", "t": [s], "axes": [{"name", "yr", "y", "u"}]} from
/// <log_dir>/<run_id>.csv; a value that is not finite is null. Throws CommandError: bad_params
/// for a run id that is not a log's name, unknown_run when there is no such log, log_too_large,
/// bad_log when its header names no t/y columns.
nlohmann::json decimated_run_log(const std::filesystem::path& log_dir, const std::string& run_id,
                                 std::size_t points);

}  // namespace hystbench::daemon::details
