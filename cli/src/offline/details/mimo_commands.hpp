#pragma once
// fit, simulate and diagnose for records of several inputs and outputs (a Hammerstein MIMO
// model); the offline commands hand over to these when the columns name several (or fit's
// --model hammerstein). fit and simulate are in mimo_commands.cpp, the cross-coupling diagnosis
// in cross_coupling_diagnosis.cpp, the records at several amplitudes in amplitude_commands.cpp.
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/offline/diagnose_command.hpp"
#include "hystbench/cli/offline/offline_commands.hpp"
#include "hystbench/compensation/mimo_identification.hpp"
#include "hystbench/compensation/mimo_model_file.hpp"

namespace hystbench::cli::details {

/// The record's realizations and periods from its `realization` and `period` columns (one
/// realization, one period where absent). Rows of a realization, and of a period, are
/// contiguous, and every period has the same length; else DataFileError naming the row.
compensation::PeriodicRecord periodic_record(const MultiRecord& data, const std::string& path);
/// periodic_record() of a record to fit dynamics on: DataFileError where its periods are shorter
/// than 16 samples.
compensation::PeriodicRecord dynamic_record(const MultiRecord& data, const std::string& path);

/// "a, b, c".
std::string joined(const std::vector<std::string>& names);
/// The model file's channels: each name with its unit, `fallback` where the record has none.
std::vector<compensation::MimoChannel> channels(
    const std::vector<std::string>& names, const std::vector<std::optional<std::string>>& units,
    const char* fallback);

/// A diagnosis's result: `result` as one JSON line, or `text`; returns exit code 0.
int print_result(std::ostream& out, bool json_output, const nlohmann::json& result,
                 const std::string& text);

/// Records of one device at several amplitudes (amplitude_commands.cpp): each with a label that
/// names where it comes from, the channels' names and units of them all.
struct AmplitudeRecords {
  std::vector<std::string> labels;
  std::vector<compensation::PeriodicRecord> records;
  std::vector<std::string> u_names, y_names;
  std::vector<std::optional<std::string>> u_units, y_units;
};
/// Every file's record; DataFileError naming a file whose units or rate differ from the first's.
AmplitudeRecords amplitude_records(const std::vector<std::string>& paths,
                                   const RecordColumns& columns);
/// One file's realizations, in groups by amplitude (compensation::amplitude_groups).
AmplitudeRecords amplitude_records(const std::string& path, const MultiRecord& data,
                                   const compensation::PeriodicRecord& record,
                                   const std::vector<std::vector<std::size_t>>& groups);

/// fit of several records (cmd.more_data_paths), or of one whose realizations are at several
/// amplitudes: runs run_fit_scheduled.
int run_fit_mimo(const FitCommand& cmd, std::ostream& out, std::ostream& err);
/// fit of records of the same device at several amplitudes: one local model each, blended by
/// the drive's amplitude.
int run_fit_scheduled(const FitCommand& cmd, const AmplitudeRecords& records, std::ostream& out,
                      std::ostream& err);
/// diagnose of records at several amplitudes: amplitude dependence, each amplitude left out in
/// turn.
int run_diagnose_amplitude(const DiagnoseCommand& cmd, const AmplitudeRecords& records,
                           std::ostream& out, std::ostream& err);
/// diagnose of a record of several inputs: cross-coupling per output; of several records (and
/// nothing else), or one whose realizations are at several amplitudes: run_diagnose_amplitude (each
/// output's own input: the one of its position, or the first where one output is given).
int run_diagnose_mimo(const DiagnoseCommand& cmd, std::ostream& out, std::ostream& err);
int run_simulate_mimo(const SimulateCommand& cmd, const compensation::MimoModelFile& file,
                      std::ostream& out, std::ostream& err);

}  // namespace hystbench::cli::details
