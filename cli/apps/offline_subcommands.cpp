// The offline commands of the `hystbench` CLI: fit, simulate, invert, diagnose and convert on
// data files, plot on a run log; no daemon needed.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "hystbench/cli/offline/convert_command.hpp"
#include "hystbench/cli/offline/diagnose_command.hpp"
#include "hystbench/cli/offline/offline_commands.hpp"
#include "hystbench/cli/report/plot_command.hpp"
#include "hystbench/common/fit_families.hpp"
#include "subcommands.hpp"

namespace cli = hystbench::cli;
namespace common = hystbench::common;

namespace {

// Column mapping shared by the commands that read a measured record.
void add_column_options(CLI::App* c, cli::RecordColumns& columns, bool y_optional) {
  c->add_option("--t-column", columns.t, "Name of the time column [s]")->capture_default_str();
  c->add_option("--u-column", columns.u,
                "Name of the input column; several, comma-separated (u1_V,u2_V,u3_V), for a "
                "record of several inputs")
      ->capture_default_str();
  c->add_option("--y-column", columns.y,
                std::string(y_optional ? "Name of the (optional) measured output column"
                                       : "Name of the measured output column") +
                    "; several, comma-separated, for several outputs. A record of several "
                    "columns may hold `realization` and `period` columns (whole numbers): "
                    "experiments that each start from rest, and the periods of a periodic "
                    "excitation (the first dropped as a transient)")
      ->capture_default_str();
  // One scale for every column, or one per column of a list.
  const auto scales = [](double& one, std::vector<double>& each) {
    return [&one, &each](const std::vector<double>& v) {
      one = v.front();
      each = v.size() > 1 ? v : std::vector<double>{};
    };
  };
  c->add_option_function<std::vector<double>>(
       "--u-scale", scales(columns.u_scale, columns.u_scales),
       "Multiply the input column by this (mV -> V: 1e-3); several columns: one for all, or "
       "one each, comma-separated (default 1)")
      ->delimiter(',');
  c->add_option_function<std::vector<double>>(
       "--y-scale", scales(columns.y_scale, columns.y_scales),
       "Multiply the output column by this (m -> um: 1e6); several columns: one for all, or "
       "one each, comma-separated (default 1)")
      ->delimiter(',');
  c->add_option("--rate", columns.rate_hz,
                "Sample rate [Hz] of a file without a time column (t = row / rate)")
      ->check(CLI::PositiveNumber);
  c->add_option("--u-unit", columns.u_unit,
                "Unit of the input after --u-scale (e.g. N); default: the column header's "
                "('F [N]', 'F_N'), else V");
  c->add_option("--y-unit", columns.y_unit,
                "Unit of the output after --y-scale (e.g. mm); default: the column header's "
                "('x [mm]', 'x_mm'), else um");
}

}  // namespace

void add_record_columns(CLI::App* cmd, const std::string& signal, std::string& t_column,
                        std::string& column, double& scale, double& rate_hz,
                        const RecordColumnsHelp& help) {
  cmd->add_option("--t-column", t_column, help.t)->capture_default_str();
  cmd->add_option("--" + signal + "-column", column, help.column)->capture_default_str();
  cmd->add_option("--" + signal + "-scale", scale, help.scale)->capture_default_str();
  cmd->add_option("--rate", rate_hz, help.rate)->check(CLI::PositiveNumber);
}

CliCommand add_fit(CLI::App& app) {
  auto fit = std::make_shared<cli::FitCommand>();
  auto* cmd =
      app.add_subcommand("fit", "Identify a hysteresis model from a measured record (t,u,y)");
  auto files = std::make_shared<std::vector<std::string>>();
  cmd->add_option("data", *files,
                  "CSV file with columns t, u, y. Records of several inputs: more than one file "
                  "holds the same device at other amplitudes (as do realizations of one file "
                  "more than 25 % apart in amplitude), each fitted on its own, the models "
                  "blended by the drive's amplitude (one model for every amplitude)")
      ->required()
      ->check(CLI::ExistingFile);
  std::vector<std::string> families = common::fit_family_name_list();
  families.push_back("hammerstein");
  cmd->add_option(
         "--model", fit->model_name,
         "Model family: pi (classical), mpi (modified, asymmetric), cpi (coupled-play), "
         "rpi (rate-dependent), preisach (relays on a grid of the Preisach plane, not a PI), "
         "auto (lowest held-out error); hammerstein (a play "
         "model per input, then linear dynamics with shared poles: the family of "
         "several inputs and outputs, which comma lists in --u-column / --y-column "
         "choose)")
      ->check(CLI::IsMember(families))
      ->capture_default_str();
  cmd->add_option("--operators", fit->operators,
                  "Number of play operators, or the Preisach plane's cells per side (0 = choose by "
                  "held-out error; the plane: 24)")
      ->check(CLI::Range(0, 500))
      ->capture_default_str();
  cmd->add_option("--deadzones", fit->dead_zones,
                  "Dead zones per side m, 2m+1 in all (-1 = choose by held-out error)")
      ->check(CLI::Range(-1, 100))
      ->capture_default_str();
  cmd->add_option("--heldout", fit->heldout_fraction,
                  "Fraction at the end of the record kept out of the fit to measure the error")
      ->check(CLI::Range(0.05, 0.9))
      ->capture_default_str();
  cmd->add_flag("!--no-refine", fit->refine, "Skip the Levenberg-Marquardt threshold refinement");
  cmd->add_option("--skip", fit->skip_s,
                  "Seconds at the start left out of fit and score (default: until the input "
                  "has reached both of its extremes, the start-up from an unknown state)")
      ->check(CLI::NonNegativeNumber);
  auto* creep_on = cmd->add_flag_callback(
      "--creep", [fit] { fit->creep = true; },
      "Always fit creep lags (default: tried, kept when they lower the held-out error)");
  cmd->add_flag_callback(
         "--no-creep", [fit] { fit->creep = false; }, "Never fit creep lags")
      ->excludes(creep_on);
  cmd->add_flag("!--no-rate-law", fit->plane_rate_law,
                "The Preisach plane: never widen its relays with the input rate (default: the "
                "thresholds law tried, kept when it lowers the held-out error by 2 %)");
  cmd->add_flag("--drift", fit->drift,
                "Fit a straight-line drift of the output over the record with the weights and "
                "leave it out of the model (a record taken while earlier creep still settled, "
                "a sensor warming up); the errors are then of the record without it");
  cmd->add_option("-o,--output", fit->output_path, "Model file to write (JSON)")->required();
  cmd->add_flag("--json", fit->json_output, "Print the result as one JSON line");
  add_column_options(cmd, fit->columns, false);
  return {cmd, [fit, files] {
            fit->data_path = files->front();
            fit->more_data_paths.assign(files->begin() + 1, files->end());
            return cli::run_fit(*fit, std::cout, std::cerr);
          }};
}

CliCommand add_simulate(CLI::App& app) {
  auto sim = std::make_shared<cli::SimulateCommand>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Run a model file over an input record; writes t,u,y_model[,y,residual] (one of each per "
      "column for a model of several inputs; by default the columns it was fitted on)");
  cmd->add_option("model", sim->model_path, "Model file (JSON)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("data", sim->data_path, "CSV with columns t, u (and y to measure the error)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", sim->output_path, "CSV file to write")->required();
  add_column_options(cmd, sim->columns, true);
  cmd->add_option("--skip", sim->skip_s,
                  "A model of several inputs: seconds at the start of each realization "
                  "simulated but not scored (the model starts from rest)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", sim->json_output,
                "Print {\"rmse\",\"max_abs\",\"range\",...} as one JSON line (when y is present)");
  return {cmd, [sim] { return cli::run_simulate(*sim, std::cout, std::cerr); }};
}

CliCommand add_invert(CLI::App& app) {
  auto inv = std::make_shared<cli::InvertCommand>();
  auto* cmd = app.add_subcommand("invert",
                                 "Compute the drive u that makes the model follow a reference yr");
  cmd->add_option("model", inv->model_path, "Model file (JSON)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("reference", inv->reference_path, "CSV with columns t, yr")
      ->required()
      ->check(CLI::ExistingFile);
  add_record_columns(cmd, "yr", inv->t_column, inv->yr_column, inv->yr_scale, inv->rate_hz,
                     {"Name of the time column [s]",
                      "Name of the reference column (the model's output unit after --yr-scale)",
                      "Multiply the reference by this (m -> um: 1e6)",
                      "Sample rate [Hz] of a file without a time column (t = row / rate)"});
  cmd->add_option("-o,--output", inv->output_path, "CSV file to write (t,yr,u)")->required();
  cmd->add_option("--inverse", inv->inverse,
                  "auto (analytic where a closed form exists, else numeric; for a rate-dependent "
                  "model (rpi) the drive is planned over the whole reference), analytic, "
                  "numeric (a rate-dependent model's looks 30 ms ahead), multiplicative "
                  "(inverse multiplicative structure)")
      ->check(CLI::IsMember({"auto", "analytic", "numeric", "multiplicative"}))
      ->capture_default_str();
  cmd->add_flag("--json", inv->json_output, "Print the result as one JSON line");
  return {cmd, [inv] { return cli::run_invert(*inv, std::cout, std::cerr); }};
}

CliCommand add_diagnose(CLI::App& app) {
  auto diag = std::make_shared<cli::DiagnoseCommand>();
  auto* cmd = app.add_subcommand(
      "diagnose",
      "Find what a model misses on records (t,u,y) of one device: asymmetry, loop_shape, "
      "rate_dependence, "
      "creep, dynamics, delay, drift or none; gains measured on held-out parts, and with "
      "several records on each record left out whole. A record of several inputs "
      "(--u-column u1,u2,...) names cross_coupling per output, each realization left out in "
      "turn; several such records at several amplitudes name amplitude_dependence (modes that "
      "move with the drive), each amplitude left out in turn");
  cmd->add_option("data", diag->data_paths,
                  "CSV with columns t, u, y (a bench run log works too); several records of one "
                  "device are diagnosed together (effects seen only across records, such as "
                  "rate dependence between runs at different frequencies; a device of several "
                  "inputs at several amplitudes)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--validate", diag->validate_paths,
                  "Record(s) never fitted: the baseline and extended models are scored on them")
      ->check(CLI::ExistingFile);
  cmd->add_option("--model", diag->model_path,
                  "Baseline model file (default: a classical PI identified on the data)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", diag->json_output, "Print the result as one JSON object");
  add_column_options(cmd, diag->columns, false);
  cmd->add_option("--report", diag->report_dir,
                  "Folder for report.txt, diagnosis.json and gnuplot PNGs");
  cmd->add_option("--save-baseline", diag->save_baseline,
                  "Write the baseline model file, when it passes its check (its inverse follows "
                  "it over its input range; else not written, exit status 1)");
  cmd->add_option("--save-extended", diag->save_extended,
                  "Write the extended model file (the baseline plus the named effects; its "
                  "mode and delay timed on the first record's step responses), when it passes "
                  "the same check");
  return {cmd, [diag] { return cli::run_diagnose(*diag, std::cout, std::cerr); }};
}

CliCommand add_convert(CLI::App& app) {
  auto conv = std::make_shared<cli::ConvertCommand>();
  auto* cmd = app.add_subcommand(
      "convert",
      "Write a record stored as NumPy arrays (inputs in one .npy, outputs in another; float64 "
      "or float32, C order) as one CSV: t,realization,period,n_in_period, then one column per "
      "input and output channel. The arrays' axes are (N, channel), (N, channel, realization) "
      "or (N, channel, realization, period), N samples per period; the two files must agree in "
      "N, realizations and periods. Rows go realization by realization, period by period; t "
      "[s] = (period * N + n_in_period) / rate starts again at 0 with each realization. Values "
      "are copied exactly (17 significant digits).\n"
      "Example (the CubeSpec mirror data, (8192, 3, 3, 2) sampled at 6400 Hz):\n"
      "  hystbench convert u_300mV_test.npy y_300mV_test.npy --rate 6400 -o fsm_300mV_test.csv");
  cmd->add_option("u", conv->u_path, "Input array (.npy), e.g. voltages")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("y", conv->y_path, "Output array (.npy), e.g. displacements")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", conv->output_path, "CSV file to write")->required();
  cmd->add_option("--rate", conv->rate_hz,
                  "Sample rate [Hz] of the arrays (the files do not store it; the CubeSpec "
                  "data's is 6400)")
      ->required()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--u-names", conv->u_names,
                  "Input column names, one per channel, comma-separated (default u1_V,u2_V,...)")
      ->delimiter(',');
  cmd->add_option("--y-names", conv->y_names,
                  "Output column names, one per channel, comma-separated (default "
                  "y1_m,y2_m,...)")
      ->delimiter(',');
  cmd->add_flag("--json", conv->json_output, "Print the result as one JSON line");
  return {cmd, [conv] { return cli::run_convert(*conv, std::cout, std::cerr); }};
}

CliCommand add_plot(CLI::App& app) {
  auto plot = std::make_shared<cli::PlotCommand>();
  auto* cmd = app.add_subcommand(
      "plot",
      "Draw a run log as PNGs (gnuplot): reference, measurement and model against time; the "
      "tracking error against time; the output-input loop with the model's loop over it.\n"
      "Example: hystbench plot /var/lib/hystbench/logs/20261125T120000Z-track-2.csv -o plots/");
  cmd->add_option("log", plot->log_path, "Run log (CSV with t, u, y; yr and y_model if any)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", plot->out_dir,
                  "Folder for the PNGs (default: the log's name with -plots, beside it)");
  cmd->add_flag("--json", plot->json_output, "Print the written files as one JSON line");
  return {cmd, [plot] { return cli::run_plot(*plot, std::cout, std::cerr); }};
}
