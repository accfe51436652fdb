#pragma once
// `hystbench convert U.npy Y.npy -o record.csv --rate HZ`: a measured record stored as NumPy
// arrays of shape (N, channel), (N, channel, realization) or (N, channel, realization, period),
// inputs in one file and outputs in the other, written as one CSV with columns
// t,realization,period,n_in_period,<input names>,<output names>. Values are copied exactly (17
// significant digits); t [s] runs on through the periods of a realization and starts again at 0
// with the next. Not real-time.
#include <iosfwd>
#include <string>
#include <vector>

namespace hystbench::cli {

struct ConvertCommand {
  std::string u_path;  ///< inputs (.npy)
  std::string y_path;  ///< outputs (.npy)
  std::string output_path;
  double rate_hz = 0.0;  ///< sample rate [Hz], > 0
  /// Column names, one per channel; empty: u1_V, u2_V, ... and y1_m, y2_m, ...
  std::vector<std::string> u_names, y_names;
  bool json_output = false;
};

/// Returns the exit code: 0 written; 1 an unreadable array, shapes that do not agree (both
/// named), a name count that is not the channel count, a repeated column name or a rate that is
/// not positive (the message says which; nothing is written).
int run_convert(const ConvertCommand& cmd, std::ostream& out, std::ostream& err);

}  // namespace hystbench::cli
