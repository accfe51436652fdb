#pragma once
// `hystbench plot RUN.csv [-o DIR]`: pictures of one run log (the daemon's sample log, or any
// CSV with t, u, y and optionally yr and y_model), written as PNGs by gnuplot:
//   time.png   reference, measurement and model prediction against time
//   error.png  tracking error y - yr against time (each point's bin min and max, so no peak is
//              lost to thinning), or y - y_model when the run had no reference
//   loop.png   output against input, with the model's loop over the measured one
// `track --wait --plot DIR` draws the same when the run ends, and learning.png for a learning
// run. Not real-time.
#include <filesystem>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hystbench::cli {

struct PlotCommand {
  std::string log_path;
  std::string out_dir;  ///< empty = "<log without .csv>-plots" beside the log
  bool json_output = false;
};

/// Writes the PNGs (and plot.dat, plot.gp, gnuplot.log beside them) into dir and returns their
/// paths. Throws DataFileError / std::runtime_error naming the cause: unreadable log, a missing
/// t, u or y column, no finite sample, gnuplot missing or failing.
std::vector<std::filesystem::path> plot_run_log(const std::string& log_path,
                                                const std::filesystem::path& dir);

/// learning.png of a learning run (`track --learn N --plot DIR`): each trial's rms and max error
/// [% of range] on a log axis, and the last trial's error against time [um] from the log's last
/// period_samples rows. `learning`: the result's learning object. Writes learning.dat,
/// learning.gp beside it; throws as plot_run_log does.
std::filesystem::path plot_learning(const nlohmann::json& learning, const std::string& log_path,
                                    const std::filesystem::path& dir);

/// The default folder for a log's plots: "<log without .csv>-plots".
std::filesystem::path default_plot_dir(const std::string& log_path);

/// Returns the exit code: 0 written, 1 the log or gnuplot failed (the message says which).
int run_plot(const PlotCommand& cmd, std::ostream& out, std::ostream& err);

}  // namespace hystbench::cli
