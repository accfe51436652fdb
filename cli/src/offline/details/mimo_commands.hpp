#pragma once
// fit, simulate and diagnose for records of several inputs and outputs (a Hammerstein MIMO
// model); the offline commands hand over to these when the columns name several (or fit's
// --model hammerstein).
#include <iosfwd>

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

int run_fit_mimo(const FitCommand& cmd, std::ostream& out, std::ostream& err);
/// diagnose of a record of several inputs: cross-coupling per output (each output's own input:
/// the one of its position, or the first where one output is given).
int run_diagnose_mimo(const DiagnoseCommand& cmd, std::ostream& out, std::ostream& err);
int run_simulate_mimo(const SimulateCommand& cmd, const compensation::MimoModelFile& file,
                      std::ostream& out, std::ostream& err);

}  // namespace hystbench::cli::details
