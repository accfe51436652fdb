// hystbench: the bench's command-line tool.
//   Offline (no daemon needed): fit, simulate, invert, diagnose on CSV files; convert .npy to CSV.
//   Bench (talks to hystbenchd over its Unix socket): status, identify, track, excite, sweep,
//   stop, abort, reset, model, config.
#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "hystbench/daemon/convert_command.hpp"
#include "hystbench/daemon/diagnose_command.hpp"
#include "hystbench/daemon/fit_families.hpp"
#include "hystbench/daemon/offline_commands.hpp"
#include "hystbench/daemon/plot_command.hpp"
#include "hystbench/daemon/remote_commands.hpp"
#include "hystbench/daemon/sweep_command.hpp"

namespace hd = hystbench::daemon;

int main(int argc, char** argv) {
  CLI::App app{
      "hystbench - identify, simulate and compensate piezo hysteresis (Prandtl-Ishlinskii family)\n"
      "\n"
      "Data files are CSV: '#' lines are comments, a header row names the columns; 't' (s) and\n"
      "'u' (input, e.g. V) are required, 'y' (output, e.g. um) where the command needs it.\n"
      "Other names, scales or no time column: --t-column, --u-column, --y-column, --u-scale,\n"
      "--y-scale, --rate (fit, simulate, diagnose). Units come from a header such as\n"
      "'F [N]' or 'x_mm', or --u-unit / --y-unit; V and um where nothing names them.\n"
      "\n"
      "Examples:\n"
      "  hystbench fit run.csv --model mpi -o actuator.json\n"
      "  hystbench simulate actuator.json other_run.csv -o predicted.csv --json\n"
      "  hystbench invert actuator.json reference.csv -o drive.csv\n"
      "  hystbench diagnose run.csv --report diagnosis/ --save-extended extended.json\n"
      "  hystbench diagnose daq.csv --u-column u1_V --y-column y1_m --y-scale 1e6 --rate 6400\n"
      "  hystbench fit mirror.csv --u-column u1_V,u2_V,u3_V --y-column y1_m,y2_m,y3_m --y-scale "
      "1e6 "
      "-o mirror.json\n"
      "  hystbench simulate mirror.json test.csv --y-scale 1e6 --skip 0.1 -o predicted.csv\n"
      "  hystbench diagnose run_1hz.csv run_5hz.csv run_20hz.csv --validate run_10hz.csv\n"
      "  hystbench convert u_300mV_test.npy y_300mV_test.npy --rate 6400 -o fsm_300mV_test.csv\n"
      "  hystbench identify --wait                  (bench: identify the actuator on the bench)\n"
      "  hystbench track --reference triangle --frequency 1 --periods 5 --compensator inverse "
      "--wait --json\n"
      "  hystbench track --reference-file raster.csv --compensator inverse --wait\n"
      "  hystbench excite --input-file drive.csv --wait   (then: hystbench fit <its log> ...)\n"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(HYSTBENCH_VERSION));

  // Column mapping shared by the commands that read a measured record.
  auto add_column_options = [](CLI::App* c, hd::RecordColumns& columns, bool y_optional) {
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
  };

  hd::FitCommand fit;
  auto* fit_cmd =
      app.add_subcommand("fit", "Identify a hysteresis model from a measured record (t,u,y)");
  fit_cmd->add_option("data", fit.data_path, "CSV file with columns t, u, y")
      ->required()
      ->check(CLI::ExistingFile);
  std::vector<std::string> fit_families = hd::fit_family_name_list();
  fit_families.push_back("hammerstein");
  fit_cmd
      ->add_option("--model", fit.model_name,
                   "Model family: pi (classical), mpi (modified, asymmetric), cpi (coupled-play), "
                   "rpi (rate-dependent), auto (lowest held-out error); hammerstein (a play "
                   "model per input, then linear dynamics with shared poles: the family of "
                   "several inputs and outputs, which comma lists in --u-column / --y-column "
                   "choose)")
      ->check(CLI::IsMember(fit_families))
      ->capture_default_str();
  fit_cmd
      ->add_option("--operators", fit.operators,
                   "Number of play operators (0 = choose by held-out error)")
      ->check(CLI::Range(0, 500))
      ->capture_default_str();
  fit_cmd
      ->add_option("--deadzones", fit.dead_zones,
                   "Dead zones per side m, 2m+1 in all (-1 = choose by held-out error)")
      ->check(CLI::Range(-1, 100))
      ->capture_default_str();
  fit_cmd
      ->add_option("--heldout", fit.heldout_fraction,
                   "Fraction at the end of the record kept out of the fit to measure the error")
      ->check(CLI::Range(0.05, 0.9))
      ->capture_default_str();
  fit_cmd->add_flag("!--no-refine", fit.refine,
                    "Skip the Levenberg-Marquardt threshold refinement");
  fit_cmd
      ->add_option("--skip", fit.skip_s,
                   "Seconds at the start left out of fit and score (default: until the input "
                   "has reached both of its extremes, the start-up from an unknown state)")
      ->check(CLI::NonNegativeNumber);
  auto* creep_on = fit_cmd->add_flag_callback(
      "--creep", [&fit] { fit.creep = true; },
      "Always fit creep lags (default: tried, kept when they lower the held-out error)");
  fit_cmd
      ->add_flag_callback(
          "--no-creep", [&fit] { fit.creep = false; }, "Never fit creep lags")
      ->excludes(creep_on);
  fit_cmd->add_flag("--drift", fit.drift,
                    "Fit a straight-line drift of the output over the record with the weights and "
                    "leave it out of the model (a record taken while earlier creep still settled, "
                    "a sensor warming up); the errors are then of the record without it");
  fit_cmd->add_option("-o,--output", fit.output_path, "Model file to write (JSON)")->required();
  fit_cmd->add_flag("--json", fit.json_output, "Print the result as one JSON line");
  add_column_options(fit_cmd, fit.columns, false);

  hd::SimulateCommand sim;
  auto* sim_cmd = app.add_subcommand(
      "simulate",
      "Run a model file over an input record; writes t,u,y_model[,y,residual] (one of each per "
      "column for a model of several inputs; by default the columns it was fitted on)");
  sim_cmd->add_option("model", sim.model_path, "Model file (JSON)")
      ->required()
      ->check(CLI::ExistingFile);
  sim_cmd->add_option("data", sim.data_path, "CSV with columns t, u (and y to measure the error)")
      ->required()
      ->check(CLI::ExistingFile);
  sim_cmd->add_option("-o,--output", sim.output_path, "CSV file to write")->required();
  add_column_options(sim_cmd, sim.columns, true);
  sim_cmd
      ->add_option("--skip", sim.skip_s,
                   "A model of several inputs: seconds at the start of each realization "
                   "simulated but not scored (the model starts from rest)")
      ->check(CLI::NonNegativeNumber);
  sim_cmd->add_flag(
      "--json", sim.json_output,
      "Print {\"rmse\",\"max_abs\",\"range\",...} as one JSON line (when y is present)");

  hd::InvertCommand inv;
  auto* inv_cmd = app.add_subcommand(
      "invert", "Compute the drive u that makes the model follow a reference yr");
  inv_cmd->add_option("model", inv.model_path, "Model file (JSON)")
      ->required()
      ->check(CLI::ExistingFile);
  inv_cmd->add_option("reference", inv.reference_path, "CSV with columns t, yr")
      ->required()
      ->check(CLI::ExistingFile);
  inv_cmd->add_option("--t-column", inv.t_column, "Name of the time column [s]")
      ->capture_default_str();
  inv_cmd
      ->add_option("--yr-column", inv.yr_column,
                   "Name of the reference column (the model's output unit after --yr-scale)")
      ->capture_default_str();
  inv_cmd->add_option("--yr-scale", inv.yr_scale, "Multiply the reference by this (m -> um: 1e6)")
      ->capture_default_str();
  inv_cmd
      ->add_option("--rate", inv.rate_hz,
                   "Sample rate [Hz] of a file without a time column (t = row / rate)")
      ->check(CLI::PositiveNumber);
  inv_cmd->add_option("-o,--output", inv.output_path, "CSV file to write (t,yr,u)")->required();
  inv_cmd
      ->add_option("--inverse", inv.inverse,
                   "auto (analytic where a closed form exists, else numeric; for a rate-dependent "
                   "model (rpi) the drive is planned over the whole reference), analytic, "
                   "numeric (a rate-dependent model's looks 30 ms ahead), multiplicative "
                   "(inverse multiplicative structure)")
      ->check(CLI::IsMember({"auto", "analytic", "numeric", "multiplicative"}))
      ->capture_default_str();
  inv_cmd->add_flag("--json", inv.json_output, "Print the result as one JSON line");

  hd::DiagnoseCommand diag;
  auto* diag_cmd = app.add_subcommand(
      "diagnose",
      "Find what a model misses on records (t,u,y) of one device: asymmetry, rate_dependence, "
      "creep, dynamics, delay, drift or none; gains measured on held-out parts, and with "
      "several records on each record left out whole. A record of several inputs "
      "(--u-column u1,u2,...) names cross_coupling per output, each realization left out in "
      "turn");
  diag_cmd
      ->add_option("data", diag.data_paths,
                   "CSV with columns t, u, y (a bench run log works too); several records of one "
                   "device are diagnosed together (effects seen only across records, such as "
                   "rate dependence between runs at different frequencies)")
      ->required()
      ->check(CLI::ExistingFile);
  diag_cmd
      ->add_option("--validate", diag.validate_paths,
                   "Record(s) never fitted: the baseline and extended models are scored on them")
      ->check(CLI::ExistingFile);
  diag_cmd
      ->add_option("--model", diag.model_path,
                   "Baseline model file (default: a classical PI identified on the data)")
      ->check(CLI::ExistingFile);
  diag_cmd->add_flag("--json", diag.json_output, "Print the result as one JSON object");
  add_column_options(diag_cmd, diag.columns, false);
  diag_cmd->add_option("--report", diag.report_dir,
                       "Folder for report.txt, diagnosis.json and gnuplot PNGs");
  diag_cmd->add_option("--save-baseline", diag.save_baseline, "Write the baseline model file");
  diag_cmd->add_option("--save-extended", diag.save_extended,
                       "Write the extended model file (the baseline plus the named effect)");

  hd::ConvertCommand conv;
  auto* conv_cmd = app.add_subcommand(
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
  conv_cmd->add_option("u", conv.u_path, "Input array (.npy), e.g. voltages")
      ->required()
      ->check(CLI::ExistingFile);
  conv_cmd->add_option("y", conv.y_path, "Output array (.npy), e.g. displacements")
      ->required()
      ->check(CLI::ExistingFile);
  conv_cmd->add_option("-o,--output", conv.output_path, "CSV file to write")->required();
  conv_cmd
      ->add_option("--rate", conv.rate_hz,
                   "Sample rate [Hz] of the arrays (the files do not store it; the CubeSpec "
                   "data's is 6400)")
      ->required()
      ->check(CLI::PositiveNumber);
  conv_cmd
      ->add_option("--u-names", conv.u_names,
                   "Input column names, one per channel, comma-separated (default u1_V,u2_V,...)")
      ->delimiter(',');
  conv_cmd
      ->add_option("--y-names", conv.y_names,
                   "Output column names, one per channel, comma-separated (default "
                   "y1_m,y2_m,...)")
      ->delimiter(',');
  conv_cmd->add_flag("--json", conv.json_output, "Print the result as one JSON line");

  // ---- bench commands (talk to hystbenchd) ----
  hd::RemoteCommand remote;
  remote.socket_path = hd::default_socket_path();
  app.add_option("--socket", remote.socket_path,
                 "hystbenchd socket (default $HYSTBENCH_SOCKET or /run/hystbench/hystbench.sock)");
  auto add_output_flags = [&remote](CLI::App* c, bool waits) {
    c->add_flag("--json", remote.json_output, "Print the result as one JSON line");
    if (waits) {
      c->add_flag("--wait", remote.wait,
                  "Show progress until the run ends, then print its result (exit 1 unless it "
                  "completed)");
    }
  };
  auto* status_cmd =
      app.add_subcommand("status", "State, active run, model, loop timing, last result");
  add_output_flags(status_cmd, false);

  std::string id_model = "";
  int id_operators = -2, id_deadzones = -2;
  bool id_no_extend = false;
  auto* identify_cmd = app.add_subcommand(
      "identify",
      "Precondition, play the identification excitation, fit a model, verify it by tracking "
      "through its inverse, make it the active model. Then the record is diagnosed with that "
      "model: what it misses (delay, dynamics, creep, rate law, asymmetry) is added where it "
      "lowers the held-out error, and the extended model is kept when it tracks better on the "
      "bench (the result lists the parts and their gains)");
  identify_cmd
      ->add_option("--model", id_model,
                   "pi, mpi, cpi, rpi or auto (every family, the best verified tracking "
                   "kept; default: the config's)")
      ->check(CLI::IsMember(hd::fit_family_name_list()));
  identify_cmd->add_option("--operators", id_operators, "Number of plays (0 = by held-out error)");
  identify_cmd->add_option("--deadzones", id_deadzones,
                           "Dead zones per side (-1 = by held-out error)");
  identify_cmd->add_flag("--no-extend", id_no_extend,
                         "Keep the fitted model as it is: no diagnosis of the record, no "
                         "extension (default: the config's [identify] extend, true)");
  add_output_flags(identify_cmd, true);

  std::string tr_reference = "triangle", tr_compensator;
  double tr_frequency = 1.0, tr_periods = 5.0, tr_duration = 0.0, tr_fraction = 0.8;
  double tr_min = NAN, tr_max = NAN, tr_precondition = NAN;
  auto* track_cmd =
      app.add_subcommand("track", "Follow a reference with a compensator and report the error");
  track_cmd
      ->add_option("--reference", tr_reference,
                   "sine, triangle, sawtooth, decaying_sine, multi_frequency, chirp")
      ->capture_default_str();
  track_cmd->add_option("--frequency", tr_frequency, "Reference frequency [Hz]")
      ->capture_default_str();
  track_cmd->add_option("--periods", tr_periods, "Number of periods")->capture_default_str();
  track_cmd->add_option("--duration", tr_duration, "Duration [s] (instead of --periods)");
  track_cmd->add_option("--compensator", tr_compensator,
                        "none, inverse, inverse_multiplicative, inverse+pid, pid (default: inverse "
                        "with a model, none without)");
  track_cmd
      ->add_option("--range-fraction", tr_fraction,
                   "Part of the actuator range the reference spans, centred")
      ->capture_default_str();
  track_cmd->add_option("--min", tr_min, "Reference minimum [um] (instead of --range-fraction)");
  track_cmd->add_option("--max", tr_max, "Reference maximum [um]");
  track_cmd->add_option("--precondition", tr_precondition,
                        "Open-loop sweep u_max -> u_min before the reference [s] (default: the "
                        "daemon's, 1 s; 0 = none)");
  int tr_learn = 0;
  double tr_learn_gain = NAN;
  auto* tr_learn_opt =
      track_cmd
          ->add_option("--learn", tr_learn,
                       "Learn over N trials (sine, triangle, sawtooth: a trial is one period; "
                       "--reference-file: one pass, its approach from the end then the "
                       "trajectory, scored on the trajectory): after a start-up period and one "
                       "with the compensator's drive, each plays the one before's drive "
                       "corrected by its measured error "
                       "(iterative learning through the model's inverse slope, delay and "
                       "dynamics). The frequency moves to the loop rate over a whole number of "
                       "ticks. The result lists every trial; the run's errors are the last "
                       "trial's; the learned drive is saved in the model folder (t,u)")
          ->check(CLI::Range(1, 1000));
  track_cmd
      ->add_option("--learn-gain", tr_learn_gain,
                   "--learn: share of the error corrected per trial at the start (default 0.5); "
                   "a trial 20 % above the best halves it, two in a row stop the learning on "
                   "the best trial's drive")
      ->check(CLI::Range(1e-3, 20.0))
      ->needs(tr_learn_opt);
  double tr_learn_cutoff = NAN;
  track_cmd
      ->add_option("--learn-cutoff", tr_learn_cutoff,
                   "--learn: the learning's low-pass cut-off [Hz] (default: the lowest of a fifth "
                   "of the loop rate, 300 x the frequency and half a modelled mode); above it "
                   "nothing is learned")
      ->check(CLI::PositiveNumber)
      ->needs(tr_learn_opt);
  std::string tr_learned;
  auto* tr_learned_opt = track_cmd->add_option(
      "--learned", tr_learned,
      "Start from a drive learned before (the learning run's id, as its result and "
      "`hystbench model list` show; also after a restart of the daemon): after the start-up "
      "period its drive plays instead of the compensator's, for one scored period, or as "
      "the first trial with --learn. Only for the reference, range and loop rate it was "
      "learned for: give the same --reference, --frequency and range (or the same "
      "--reference-file), with the model it was learned with loaded");
  for (const char* other : {"--periods", "--duration"}) {
    tr_learn_opt->excludes(track_cmd->get_option(other));
    tr_learned_opt->excludes(track_cmd->get_option(other));
  }
  add_output_flags(track_cmd, true);
  track_cmd->add_option("--plot", remote.plot_dir,
                        "With --wait: write the run's plots (time.png, error.png, loop.png) here "
                        "when it ends, as `hystbench plot` does; with --learn also learning.png "
                        "(the error per trial, and the last trial's error)");
  // A user's trajectory instead of a built-in reference: read here, uploaded over the socket.
  std::string tr_file, tr_t_column = "t", tr_yr_column = "yr";
  double tr_yr_scale = 1.0, tr_rate = 0.0, tr_approach = NAN;
  auto* tr_file_opt =
      track_cmd
          ->add_option("--reference-file", tr_file,
                       "Follow your own trajectory: a CSV with columns t [s] and yr [um] (an AFM "
                       "raster line, a recorded motion). The daemon resamples it to the loop "
                       "rate and refuses it, naming the first offending row, when it leaves the "
                       "actuator range or moves faster than the slew limit")
          ->check(CLI::ExistingFile);
  for (const char* other : {"--reference", "--frequency", "--periods", "--duration",
                            "--range-fraction", "--min", "--max"}) {
    tr_file_opt->excludes(track_cmd->get_option(other));
  }
  track_cmd->add_option("--t-column", tr_t_column, "--reference-file: time column [s]")
      ->capture_default_str();
  track_cmd->add_option("--yr-column", tr_yr_column, "--reference-file: reference column")
      ->capture_default_str();
  track_cmd
      ->add_option("--yr-scale", tr_yr_scale,
                   "--reference-file: multiply the reference by this (m -> um: 1e6)")
      ->capture_default_str();
  track_cmd
      ->add_option("--rate", tr_rate,
                   "--reference-file: sample rate [Hz] of a file without a time column")
      ->check(CLI::PositiveNumber);
  track_cmd->add_option("--approach", tr_approach,
                        "--reference-file: unscored move from the precondition's end to the "
                        "first value [s] (default 0.2, longer when the slew limit needs it)");

  hd::RecordColumns ex_columns;
  ex_columns.y.clear();
  std::string ex_file;
  auto* excite_cmd = app.add_subcommand(
      "excite",
      "Play your own open-loop drive (t [s], u [V]) and log every sample: the run log is a "
      "record that `hystbench fit` and `diagnose` read as it is");
  excite_cmd
      ->add_option("--input-file", ex_file,
                   "CSV with columns t [s] and u [V]; refused, naming the first offending row, "
                   "when it leaves [u_min, u_max] or moves faster than the slew limit")
      ->required()
      ->check(CLI::ExistingFile);
  excite_cmd->add_option("--t-column", ex_columns.t, "Time column [s]")->capture_default_str();
  excite_cmd->add_option("--u-column", ex_columns.u, "Drive column")->capture_default_str();
  excite_cmd
      ->add_option("--u-scale", ex_columns.u_scale, "Multiply the drive by this (mV -> V: 1e-3)")
      ->capture_default_str();
  excite_cmd
      ->add_option("--rate", ex_columns.rate_hz,
                   "Sample rate [Hz] of a file without a time column (t = row / rate)")
      ->check(CLI::PositiveNumber);
  add_output_flags(excite_cmd, true);

  hd::PlotCommand plot;
  auto* plot_cmd = app.add_subcommand(
      "plot",
      "Draw a run log as PNGs (gnuplot): reference, measurement and model against time; the "
      "tracking error against time; the output-input loop with the model's loop over it.\n"
      "Example: hystbench plot /var/lib/hystbench/logs/20261125T120000Z-track-2.csv -o plots/");
  plot_cmd->add_option("log", plot.log_path, "Run log (CSV with t, u, y; yr and y_model if any)")
      ->required()
      ->check(CLI::ExistingFile);
  plot_cmd->add_option("-o,--output", plot.out_dir,
                       "Folder for the PNGs (default: the log's name with -plots, beside it)");
  plot_cmd->add_flag("--json", plot.json_output, "Print the written files as one JSON line");

  hd::SweepCommand sweep;
  auto* sweep_cmd = app.add_subcommand(
      "sweep",
      "Track a reference at each of a list of frequencies with each compensator and print one "
      "table of the tracking error (rms / max, % of range): how a stage behaves with frequency.\n"
      "Example: hystbench sweep --frequencies 1,5,10,19,50,100,200 --compensators "
      "none,inverse,inverse+pid --plot sweep/");
  sweep_cmd->add_option("--frequencies", sweep.frequencies_hz, "Reference frequencies [Hz]")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sweep_cmd
      ->add_option("--compensators", sweep.compensators,
                   "Compensators, each run at every frequency (none, inverse, "
                   "inverse_multiplicative, inverse+pid, pid)")
      ->delimiter(',')
      ->check(CLI::IsMember({"none", "inverse", "inverse_multiplicative", "inverse+pid", "pid"}))
      ->capture_default_str();
  sweep_cmd->add_option("--reference", sweep.reference, "sine, triangle, sawtooth")
      ->check(CLI::IsMember({"sine", "triangle", "sawtooth"}))
      ->capture_default_str();
  sweep_cmd->add_option("--periods", sweep.periods, "Periods per run (the first is not scored)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sweep_cmd
      ->add_option("--min-duration", sweep.min_duration_s,
                   "Each run lasts at least this long [s] (more periods at high frequency)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sweep_cmd
      ->add_option("--range-fraction", sweep.range_fraction,
                   "Part of the actuator range the reference spans, centred")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str();
  sweep_cmd->add_option("--plot", sweep.plot_dir,
                        "Write sweep.png (error against frequency, log axes) and its data here");
  sweep_cmd
      ->add_option("--learn", sweep.learn_trials,
                   "Add a column 'learned': at each frequency a `track --learn N` run from the "
                   "daemon's default compensator (a trial is one period; the frequency moves to "
                   "the loop rate over a whole number of ticks), its last trial's error")
      ->check(CLI::Range(1, 1000));
  sweep_cmd->add_flag("--json", sweep.json_output, "Print one JSON object instead of the table");

  auto* stop_cmd = app.add_subcommand("stop", "End the active run normally (its result is kept)");
  add_output_flags(stop_cmd, false);
  auto* abort_cmd = app.add_subcommand("abort", "Safe output now; the active run ends as aborted");
  add_output_flags(abort_cmd, false);
  auto* reset_cmd = app.add_subcommand("reset", "Leave FAULT after the cause is fixed");
  add_output_flags(reset_cmd, false);
  auto* model_cmd =
      app.add_subcommand("model", "Show, list, load or delete the models in the daemon's folder");
  model_cmd->require_subcommand(1);
  auto* model_get = model_cmd->add_subcommand("get", "Print the active model file");
  std::string model_path, stored_model;
  auto* model_load = model_cmd->add_subcommand(
      "load",
      "Make a model active: a model file here (read by this command and sent to the daemon, "
      "which keeps a copy in its model folder), or --stored NAME from that folder");
  auto* model_file_opt =
      model_load->add_option("file", model_path, "Model file (JSON, from fit, diagnose, identify)")
          ->check(CLI::ExistingFile);
  model_load
      ->add_option("--stored", stored_model,
                   "Name of a model in the daemon's model folder (see `hystbench model list`)")
      ->excludes(model_file_opt);
  auto* model_list = model_cmd->add_subcommand("list", "The models in the daemon's model folder");
  std::string deleted_model;
  auto* model_delete = model_cmd->add_subcommand(
      "delete",
      "Delete a model or a learned drive (its JSON and CSV) from the daemon's model folder; "
      "never the active model");
  model_delete->add_option("name", deleted_model, "Its name, as `hystbench model list` shows")
      ->required();
  add_output_flags(model_delete, false);
  add_output_flags(model_get, false);
  add_output_flags(model_load, false);
  add_output_flags(model_list, false);
  auto* config_cmd = app.add_subcommand("config", "Print the daemon's effective configuration");
  add_output_flags(config_cmd, false);

  CLI11_PARSE(app, argc, argv);

  auto remote_run = [&](const std::string& cmd, nlohmann::json params) {
    remote.cmd = cmd;
    remote.params = std::move(params);
    return hd::run_remote(remote, std::cout, std::cerr);
  };
  if (*status_cmd) return remote_run("status", nlohmann::json::object());
  if (*identify_cmd) {
    nlohmann::json p = nlohmann::json::object();
    if (!id_model.empty()) p["model"] = id_model;
    if (id_operators != -2) p["operators"] = id_operators;
    if (id_deadzones != -2) p["dead_zones"] = id_deadzones;
    if (id_no_extend) p["extend"] = false;
    return remote_run("identify", p);
  }
  if (*track_cmd) {
    if (!remote.plot_dir.empty() && !remote.wait) {
      std::cerr << "hystbench: error: track --plot needs --wait (the plots are drawn when the run "
                   "ends; or run `hystbench plot LOG` afterwards)\n";
      return 2;
    }
    // --learn and --learned into the request; false when neither is given.
    const auto add_learning = [&](nlohmann::json& p) {
      if (!tr_learned.empty()) p["learned"] = tr_learned;
      if (tr_learn > 0) {
        p["learn_trials"] = tr_learn;
        if (!std::isnan(tr_learn_gain)) p["learn_gain"] = tr_learn_gain;
        if (!std::isnan(tr_learn_cutoff)) p["learn_cutoff_hz"] = tr_learn_cutoff;
      }
      return tr_learn > 0 || !tr_learned.empty();
    };
    if (!tr_file.empty()) {
      nlohmann::json p = nlohmann::json::object();
      if (!tr_compensator.empty()) p["compensator"] = tr_compensator;
      if (!std::isnan(tr_precondition)) p["precondition_s"] = tr_precondition;
      if (!std::isnan(tr_approach)) p["approach_s"] = tr_approach;
      add_learning(p);
      try {
        remote.upload =
            hd::read_upload(tr_file, "reference", tr_t_column, tr_yr_column, tr_yr_scale, tr_rate);
      } catch (const std::exception& e) {
        std::cerr << "hystbench: error: " << e.what() << "\n";
        return 1;
      }
      return remote_run("track", p);
    }
    nlohmann::json p = {{"reference", tr_reference}, {"frequency_hz", tr_frequency}};
    if (add_learning(p)) {
      // a learning run, or a learned drive's (its start-up period and one scored period)
    } else if (tr_duration > 0) {
      p["duration_s"] = tr_duration;
    } else {
      p["periods"] = tr_periods;
    }
    if (!tr_compensator.empty()) p["compensator"] = tr_compensator;
    if (!std::isnan(tr_precondition)) p["precondition_s"] = tr_precondition;
    if (!std::isnan(tr_min) || !std::isnan(tr_max)) {
      if (!std::isnan(tr_min)) p["min_um"] = tr_min;
      if (!std::isnan(tr_max)) p["max_um"] = tr_max;
    } else {
      p["range_fraction"] = tr_fraction;
    }
    return remote_run("track", p);
  }
  if (*excite_cmd) {
    try {
      remote.upload = hd::read_upload(ex_file, "drive", ex_columns.t, ex_columns.u,
                                      ex_columns.u_scale, ex_columns.rate_hz);
    } catch (const std::exception& e) {
      std::cerr << "hystbench: error: " << e.what() << "\n";
      return 1;
    }
    return remote_run("excite", nlohmann::json::object());
  }
  if (*plot_cmd) return hd::run_plot(plot, std::cout, std::cerr);
  if (*sweep_cmd) {
    sweep.socket_path = remote.socket_path;
    return hd::run_sweep(sweep, std::cout, std::cerr);
  }
  if (*stop_cmd) return remote_run("stop", nlohmann::json::object());
  if (*abort_cmd) return remote_run("abort", nlohmann::json::object());
  if (*reset_cmd) return remote_run("reset", nlohmann::json::object());
  if (*model_get) return remote_run("model.get", nlohmann::json::object());
  // The daemon resolves paths from its own folder: send the file as the user named it here.
  if (*model_list) return remote_run("model.list", nlohmann::json::object());
  if (*model_delete) return remote_run("model.delete", {{"name", deleted_model}});
  if (*model_load) {
    if (!stored_model.empty()) return remote_run("model.load", {{"stored", stored_model}});
    if (model_path.empty()) {
      std::cerr << "hystbench: error: model load: give a model file or --stored NAME\n";
      return 2;
    }
    // The file is read here, with the user's rights, and its document travels over the
    // socket: the daemon (its own user, its own /tmp and no /home) never opens a client's path.
    nlohmann::json document;
    try {
      document = hd::read_model_document(model_path);
    } catch (const std::exception& e) {
      std::cerr << "hystbench: error: " << e.what() << "\n";
      return 1;
    }
    return remote_run("model.load",
                      {{"model", std::move(document)},
                       {"name", std::filesystem::path(model_path).filename().string()}});
  }
  if (*config_cmd) return remote_run("config.get", nlohmann::json::object());

  if (*fit_cmd) return hd::run_fit(fit, std::cout, std::cerr);
  if (*sim_cmd) return hd::run_simulate(sim, std::cout, std::cerr);
  if (*inv_cmd) return hd::run_invert(inv, std::cout, std::cerr);
  if (*diag_cmd) return hd::run_diagnose(diag, std::cout, std::cerr);
  if (*conv_cmd) return hd::run_convert(conv, std::cout, std::cerr);
  return 2;
}
