#pragma once
// A learned drive in the daemon's model folder: one period of feedforward, RUN-learned.csv
// (t [s], u [input unit], and u_compensator: the compensator's own feedforward in the run that
// learned it, by which a replay moves the drive with the output offset it measures) beside
// RUN-learned.json (what it was learned for: the reference's kind, its period in ticks at the loop
// rate, its span, the trial it came from). A client names one (`track --learned NAME`, NAME = RUN,
// RUN-learned or either file's name), never a path. A drive belongs to its reference and its loop
// rate: check_learned_drive refuses another. Errors are CommandError naming the key (bad_params,
// io_error). File I/O: control thread only.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hystbench::daemon::details {

/// What a drive was learned for.
struct LearnedFor {
  std::string reference;  ///< sine, triangle, sawtooth or upload
  std::size_t period_samples = 0;
  double frequency_hz = 0.0;          ///< the loop rate / period_samples
  double rate_hz = 0.0;               ///< the loop rate
  double min_um = 0.0, max_um = 0.0;  ///< the reference's extremes
  std::string signature;              ///< an upload's fingerprint (empty for a built-in one)
};

struct LearnedDrive {
  std::string name;                 ///< RUN-learned
  std::vector<double> u;            ///< one period, period_samples values
  std::vector<double> compensator;  ///< the compensator's feedforward then, as many
  LearnedFor learned_for;
  nlohmann::json meta;  ///< the JSON file as saved
};

/// Writes RUN-learned.csv and RUN-learned.json into dir (created when missing); `meta` is added
/// to the JSON beside what the drive was learned for. Returns the CSV's path. Throws io_error.
std::string save_learned_drive(const std::string& dir, const std::string& run_id,
                               const std::vector<double>& u, const std::vector<double>& compensator,
                               double dt_s, const LearnedFor& f, const nlohmann::json& meta);

/// The learned drive `name` (request key "learned"). Throws bad_params for a name that is not
/// one or names no drive, io_error for files that do not hold one (the CSV's rows must be the
/// period's, every u finite).
LearnedDrive load_learned_drive(const std::string& dir, const std::string& name);

/// Throws bad_params when `run` is not what `drive` was learned for: another reference kind,
/// period (frequency), loop rate, extremes (beyond 1e-6 of the span) or uploaded trajectory
/// (signature); the message names both.
void check_learned_drive(const LearnedDrive& drive, const LearnedFor& run);

/// True for a model-folder file name that is a learned drive's JSON (RUN-learned.json).
bool is_learned_drive_file(const std::string& file_name);

}  // namespace hystbench::daemon::details
