#pragma once
// `hystbench diagnose DATA.csv [MORE.csv ...] [--validate OTHER.csv ...] [--model MODEL.json]
//                     [--json] [--report DIR] [--save-baseline FILE] [--save-extended FILE]`
// Reads one or more records of one device (columns t, u, y; bench run logs work too), runs
// compensation::diagnose() and prints a short readable report, or one JSON object with --json:
//   {"cause": "<name>", "verdict": "..", "heldout": "<how the record was split>",
//    "causes": [{"cause": .., "gain": .., "against": "the baseline" | "the loop's shape ..",
//                "heldout_rms": .., "added_gain": .., "added_rms": .., "evidence": "..",
//                "extension": ".."}, ...],
//    "units": {"input": "V", "output": "um"}, "noise_allowance_rms": ..,
//    "records": [{"data": path, "start": sample, "samples": n}, ...],
//    "baseline": {"model": {model file}, "description": "..", "rmse": .., "max_abs": .., ...},
//    "extended": {"model": {model file}, "description": "..", "rmse": .., "gain": .., ...},
//    "candidates": [{"cause": .., "statistic": .., "threshold": .., "significant": ..,
//                    "rmse_heldout": .., "gain": .., "evidence": "..", "extension": "..",
//                    "carries_over": .., "left_out_gain": ..,
//                    "left_out": [{"record", "baseline_rms", "rms", "gain"}, ...],
//                    "named": .., "not_named": "why not, or empty"}, ...],
//    "validation": [{"data": path, "baseline_rms": .., "extended_rms": .., "gain": ..,
//                    "baseline_offset": .., "extended_offset": .., "samples": ..}, ...],
//    "residual_structure": {"time": share, "input": .., ...}, "noise_rms": .., "notes": [..]}
// (rmse on the held-out part; gain = baseline rmse / candidate rmse; causes: every named cause,
// largest gain first, `cause` the first; every figure in the units of `units`: the records'
// headers or --u-unit / --y-unit, a given model's, else V and um). Several records are
// diagnosed together: fitted on every record's fit blocks, and every candidate also scored on
// each record left out whole (left_out; empty for one record). --validate scores the baseline
// and extended models on records that are never fitted (mean error removed, reported apart).
// --report DIR writes report.txt, diagnosis.json, the plotted data, report.gp and the gnuplot
// PNGs: loops.png (y against u with both models), residual_time.png (residual against time,
// before and after), cause_<variable>.png (baseline residual against the named cause's
// explanatory variable: input, rate, since_event, frequency or time), heldout_errors.png
// (held-out error of the baseline and of each candidate); gnuplot runs as a subprocess.
// --save-baseline / --save-extended write model files `simulate` and `invert` load. Returns the
// process exit code (0 ok, 1 error); not real-time code.
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::cli {

struct DiagnoseCommand {
  std::vector<std::string> data_paths;      ///< one or more records of one device
  std::vector<std::string> validate_paths;  ///< records only scored, never fitted
  std::string model_path;  ///< empty: the baseline is a classical PI identified on the data
  bool json_output = false;
  std::string report_dir;     ///< empty: no report
  std::string save_baseline;  ///< empty: not saved
  std::string save_extended;  ///< empty: not saved
  RecordColumns columns;      ///< which columns are t, u, y (default t, u, y)
};

int run_diagnose(const DiagnoseCommand& cmd, std::ostream& out, std::ostream& err);

/// The --json object (see above); `data_path` is recorded in it.
nlohmann::json diagnosis_to_json(const compensation::Diagnosis& d, const std::string& data_path);

/// The readable report (what `diagnose` prints without --json).
void print_diagnosis(std::ostream& out, const compensation::Diagnosis& d,
                     const std::string& data_path);

/// Writes the report folder (created if needed) and runs gnuplot on it. Throws
/// std::runtime_error naming the file or the gnuplot failure.
void write_diagnosis_report(const std::string& dir, const compensation::Diagnosis& d,
                            const std::string& data_path, std::span<const double> t,
                            std::span<const double> u, std::span<const double> y);

}  // namespace hystbench::cli
