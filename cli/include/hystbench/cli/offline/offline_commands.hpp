#pragma once
// The offline commands of the `hystbench` CLI: fit, simulate, invert on CSV files. fit and
// simulate also take records of several inputs and outputs (comma lists of columns).
// Each returns a process exit code and writes human-readable text (or one JSON line with
// `json_output`) to `out`, progress and errors to `err`.
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/common/model_file_io.hpp"  // the model files the commands read and write
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/model_file.hpp"

namespace hystbench::cli {

struct FitCommand {
  std::string data_path;
  /// Records of several inputs only: the same device at other amplitudes. Every record is fitted
  /// on its own and the models blended by the drive's amplitude (type
  /// "mimo_amplitude_scheduled"): one model for every amplitude.
  std::vector<std::string> more_data_paths;
  /// pi | mpi | cpi | rpi | preisach | auto, or hammerstein: operators per input, then linear
  /// dynamics (the family of several inputs or outputs, which comma lists in columns.u / columns.y
  /// choose)
  std::string model_name = "mpi";
  int operators = 0;    ///< 0 = chosen by held-out error
  int dead_zones = -1;  ///< -1 = chosen by held-out error
  double heldout_fraction = 0.25;
  bool refine = true;
  /// Seconds at the start neither fitted nor scored; unset = until the input has reached both
  /// of its extremes (the record's start-up from an unknown state).
  std::optional<double> skip_s;
  /// Creep lags: true = always fitted, false = never, unset = kept when held-out error improves.
  std::optional<bool> creep;
  /// Fit a straight-line output drift with the weights and leave it out of the model
  /// (FitOptions::drift): a record taken while earlier creep still settled or a sensor warmed.
  bool drift = false;
  bool plane_rate_law = true;  ///< the Preisach plane: try its relays widening with the rate
  std::string output_path;
  bool json_output = false;
  RecordColumns columns;  ///< which columns are t, u, y (default t, u, y)
};

struct SimulateCommand {
  std::string model_path;
  std::string data_path;
  std::string output_path;
  bool json_output = false;
  RecordColumns columns;  ///< which columns are t, u and the optional y
  /// A model of several inputs: seconds at the start of each realization simulated but not
  /// scored (the model starts from rest, the record did not). Unset: 0.
  std::optional<double> skip_s;
};

struct InvertCommand {
  std::string model_path;
  std::string reference_path;
  std::string output_path;
  std::string inverse = "auto";  ///< auto | analytic | numeric | multiplicative
  bool json_output = false;
  std::string t_column = "t";    ///< time column [s]
  std::string yr_column = "yr";  ///< reference column, in the model's output unit after scaling
  double yr_scale = 1.0;         ///< yr = column * yr_scale (e.g. 1e6 for m -> um)
  double rate_hz = 0.0;          ///< > 0: the file has no time column; t = row / rate_hz [s]
};

int run_fit(const FitCommand& cmd, std::ostream& out, std::ostream& err);
int run_simulate(const SimulateCommand& cmd, std::ostream& out, std::ostream& err);
int run_invert(const InvertCommand& cmd, std::ostream& out, std::ostream& err);

}  // namespace hystbench::cli
