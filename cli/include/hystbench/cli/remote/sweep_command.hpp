#pragma once
// `hystbench sweep`: characterises a stage by tracking a reference at a list of frequencies with
// one or more compensators on the bench (one `track` run each, in order), then prints one table
// of rms and max tracking error (% of range) per frequency and compensator, or one JSON object,
// and optionally a gnuplot PNG of error against frequency (log axis).
#include <iosfwd>
#include <string>
#include <vector>

namespace hystbench::cli {

struct SweepCommand {
  std::string socket_path;
  std::vector<double> frequencies_hz{1.0, 5.0, 10.0, 19.0, 50.0, 100.0, 200.0};
  std::vector<std::string> compensators{"none", "inverse"};
  std::string reference = "sine";
  double periods = 5.0;         ///< per run; raised so that every run lasts min_duration_s
  double min_duration_s = 1.0;  ///< [s]
  double range_fraction = 0.8;  ///< (0, 1]
  /// > 0: a column "learned" beside the compensators: at each frequency a `track --learn N`
  /// run from the daemon's default compensator, its last trial's error (0 = none).
  int learn_trials = 0;
  bool json_output = false;
  std::string plot_dir;  ///< empty = no plot; else sweep.dat, sweep.gp and sweep.png there
};

/// Returns the exit code: 0 every run completed, 1 a run was refused or did not complete (the
/// table so far is still printed), 2 the daemon cannot be reached or the plot cannot be written.
int run_sweep(const SweepCommand& cmd, std::ostream& out, std::ostream& err);

}  // namespace hystbench::cli
