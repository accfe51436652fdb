// The bench commands of the `hystbench` CLI: they talk to hystbenchd over its socket.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/remote/remote_commands.hpp"
#include "hystbench/cli/remote/sweep_command.hpp"
#include "hystbench/common/fit_families.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/common/request_limits.hpp"
#include "hystbench/common/run_requests.hpp"
#include "subcommands.hpp"

namespace cli = hystbench::cli;
namespace common = hystbench::common;

// --json, and --wait for a command that starts a run.
void add_output_flags(CLI::App* c, cli::RemoteCommand& remote, bool waits) {
  c->add_flag("--json", remote.json_output, "Print the result as one JSON line");
  if (waits) {
    c->add_flag("--wait", remote.wait,
                "Show progress until the run ends, then print its result (exit 1 unless it "
                "completed)");
  }
}

CLI::Validator at_least(double lo) {
  std::ostringstream name;
  name << "FLOAT >= " << lo;
  return CLI::Validator(
      [lo](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return "not a number: " + text;
        if (!(v >= lo)) {
          std::ostringstream why;
          why << "value " << text << " is below " << lo;
          return why.str();
        }
        return std::string();
      },
      name.str());
}

// Sends the daemon `cmd` with `params`; returns the exit code of run_remote.
int send_request(cli::RemoteCommand& remote, const std::string& cmd, nlohmann::json params) {
  remote.cmd = cmd;
  remote.params = std::move(params);
  return cli::run_remote(remote, std::cout, std::cerr);
}

CliCommand add_plain_request(CLI::App& parent, cli::RemoteCommand& remote, const std::string& name,
                             const std::string& description, const std::string& request) {
  auto* cmd = parent.add_subcommand(name, description);
  add_output_flags(cmd, remote, false);
  return {cmd,
          [&remote, request] { return send_request(remote, request, nlohmann::json::object()); }};
}

namespace {

// identify's choices; unset ones are the daemon's configuration's.
struct IdentifyOptions {
  std::string model;
  int operators = -2, dead_zones = -2;  ///< -2: the daemon's
  bool no_extend = false;
};

}  // namespace

CliCommand add_identify(CLI::App& app, cli::RemoteCommand& remote) {
  auto id = std::make_shared<IdentifyOptions>();
  auto* cmd = app.add_subcommand(
      "identify",
      "Precondition, play the identification excitation, fit a model, verify it by tracking "
      "through its inverse, make it the active model. Then the record is diagnosed with that "
      "model: what it misses (delay, dynamics, creep, rate law, asymmetry, the loop's shape: the "
      "operator swapped for a Preisach plane unless --model names the family) is added where it "
      "lowers the held-out error, and the extended model is kept when it tracks better on the "
      "bench (the result lists the parts and their gains)");
  add_request_option(cmd, "--model", id->model, common::kIdentifyParams, "model",
                     "pi, mpi, cpi, rpi, preisach (relays on a grid of the Preisach plane, with "
                     "creep lags; holds a loop no play family does) or auto (every family, the "
                     "best verified tracking kept); named, the extension keeps the family, left "
                     "out it may swap the operator")
      ->check(CLI::IsMember(common::fit_family_name_list()));
  add_request_option(cmd, "--operators", id->operators, common::kIdentifyParams, "operators",
                     "Number of plays, or the Preisach plane's cells per side (0 = by held-out "
                     "error; the plane: 24)");
  add_request_option(cmd, "--deadzones", id->dead_zones, common::kIdentifyParams, "dead_zones",
                     "Dead zones per side (-1 = by held-out error)");
  cmd->add_flag("--no-extend", id->no_extend,
                "Keep the fitted model as it is: no diagnosis of the record, no "
                "extension (default: the config's [identify] extend, true)");
  add_output_flags(cmd, remote, true);
  return {cmd, [id, &remote] {
            nlohmann::json p = nlohmann::json::object();
            if (!id->model.empty()) p["model"] = id->model;
            if (id->operators != -2) p["operators"] = id->operators;
            if (id->dead_zones != -2) p["dead_zones"] = id->dead_zones;
            if (id->no_extend) p["extend"] = false;
            return send_request(remote, "identify", p);
          }};
}

namespace {

// track: a built-in reference or a reference file, the compensator, learning.
struct TrackOptions {
  std::string reference, compensator;
  std::vector<double> frequencies;  // a stage's reference
  bool no_decouple = false;
  std::string decoupling;
  double frequency = NAN, periods = NAN, duration = 0.0, fraction = NAN;
  double min = NAN, max = NAN, precondition = NAN;
  int learn = 0;
  double learn_gain = NAN, learn_cutoff = NAN, lead_in_max = NAN;
  std::string learned;
  // A user's trajectory instead of a built-in reference: read here, uploaded over the socket.
  std::string file, t_column = "t", yr_column = "yr";
  double yr_scale = 1.0, rate = 0.0, approach = NAN;
  // Feedback gains by hand, instead of the designed loop.
  double kp = NAN, ki = NAN, kd = NAN;
  bool force_gains = false;
};

// track's hand gains for inverse+pid and pid.
void add_track_gain_options(CLI::App* cmd, TrackOptions& tr) {
  add_request_option(cmd, "--kp", tr.kp, common::kTrackBuiltinParams, "kp",
                     "inverse+pid, pid: proportional gain [V/um] instead of the designed loop "
                     "(checked against the loop's targets on the measured responses; `hystbench "
                     "tune --kp ...` prints its margins)");
  add_request_option(cmd, "--ki", tr.ki, common::kTrackBuiltinParams, "ki",
                     "inverse+pid, pid: integral gain [V/(um s)], as --kp");
  add_request_option(cmd, "--kd", tr.kd, common::kTrackBuiltinParams, "kd",
                     "inverse+pid, pid: derivative gain [V s/um], as --kp");
  cmd->add_flag("--force-gains", tr.force_gains,
                "Run gains that break the loop's targets (refused otherwise, naming their "
                "margins)");
}

// The hand gains into the request.
void add_gains(const TrackOptions& tr, nlohmann::json& p) {
  if (!std::isnan(tr.kp)) p["kp"] = tr.kp;
  if (!std::isnan(tr.ki)) p["ki"] = tr.ki;
  if (!std::isnan(tr.kd)) p["kd"] = tr.kd;
  if (tr.force_gains) p["force_gains"] = true;
}

// track's built-in reference: its shape, frequency, length and range.
void add_track_reference_options(CLI::App* cmd, TrackOptions& tr) {
  add_request_option(cmd, "--reference", tr.reference, common::kTrackBuiltinParams, "reference",
                     "sine, triangle, sawtooth, step (a square wave: a step up and one down each "
                     "period; the result gives their settling time to 1 % and overshoot), "
                     "decaying_sine, multi_frequency, chirp. On a stage of several axes: raster "
                     "(the first axis's lines at 10 Hz over a 0.1 Hz frame of the second), "
                     "lissajous (10, 11, ... Hz), spiral (10 turns/s closing in over --duration); "
                     "each axis over --range-fraction of its range");
  add_request_option(cmd, "--frequencies", tr.frequencies, common::kTrackBuiltinParams,
                     "frequencies_hz",
                     "On a stage: the reference's frequencies [Hz]: raster FAST,SLOW; lissajous "
                     "one per axis; spiral TURNS_PER_S")
      ->delimiter(',');
  cmd->add_flag("--no-decouple", tr.no_decouple,
                "On a stage: leave the coupling in the feedforward's targets (by default each "
                "axis's target has the other axes' share taken out, from identify's estimate)");
  add_request_option(cmd, "--decoupling", tr.decoupling, common::kTrackBuiltinParams, "decoupling",
                     "On a stage: static (the coupling's gains, from identify's estimate) or "
                     "dynamic (each coupling path's modes and lag too, fitted to the responses "
                     "identify measured; the result's decoupling.dynamic names them)")
      ->check(CLI::IsMember({"static", "dynamic"}))
      ->excludes("--no-decouple");
  const auto& t = common::kTrackBuiltinParams;
  add_request_option(cmd, "--frequency", tr.frequency, t, "frequency_hz",
                     "Reference frequency [Hz], at most a twentieth of the loop rate");
  add_request_option(cmd, "--periods", tr.periods, t, "periods", "Number of periods");
  add_request_option(cmd, "--duration", tr.duration, t, "duration_s",
                     "Duration [s] (instead of --periods)");
  add_request_option(cmd, "--compensator", tr.compensator, t, "compensator",
                     "none, inverse, inverse_multiplicative, inverse+pid, pid");
  add_request_option(cmd, "--range-fraction", tr.fraction, t, "range_fraction",
                     "Part of the actuator range the reference spans, centred");
  add_request_option(cmd, "--min", tr.min, t, "min_um",
                     "Reference minimum [um] (instead of --range-fraction)");
  add_request_option(cmd, "--max", tr.max, t, "max_um", "Reference maximum [um]");
  add_request_option(cmd, "--precondition", tr.precondition, t, "precondition_s",
                     "Open-loop sweep u_max -> u_min before the reference [s] (0 = none)");
}

// track --learn and its settings, and --learned.
void add_track_learning_options(CLI::App* cmd, TrackOptions& tr) {
  auto* learn_opt =
      cmd->add_option("--learn", tr.learn,
                      "Learn over N trials (sine, triangle, sawtooth: a trial is one period; "
                      "--reference-file: one pass, its approach from the end then the "
                      "trajectory, scored on the trajectory): after a start-up period and one "
                      "with the compensator's drive, each plays the one before's drive "
                      "corrected by its measured error "
                      "(iterative learning through the model's inverse slope and delay, "
                      "below its mode). The frequency moves to the loop rate over a whole "
                      "number of ticks. The result lists every trial; the run's errors are "
                      "the last trial's; the learned drive is saved in the model folder (t,u)")
          ->check(CLI::Range(1, 1000));
  const auto& t = common::kTrackBuiltinParams;
  add_request_option(cmd, "--learn-gain", tr.learn_gain, t, "learn_gain",
                     "--learn: share of the error corrected per trial at the start; a trial 20 % "
                     "above the best halves it, two in a row stop the learning on the best "
                     "trial's drive")
      ->needs(learn_opt);
  add_request_option(cmd, "--learn-cutoff", tr.learn_cutoff, t, "learn_cutoff_hz",
                     "--learn: the learning's low-pass cut-off [Hz], at most 0.45 of the loop "
                     "rate (by default the lowest of a fifth of the loop rate, 300 x the "
                     "frequency and half a modelled mode); above it nothing is learned")
      ->needs(learn_opt);
  auto* learned_opt = cmd->add_option(
      "--learned", tr.learned,
      "Start from a drive learned before (the learning run's id, as its result and "
      "`hystbench model list` show; also after a restart of the daemon): its drive plays "
      "instead of the compensator's through the start-up (one period, or 20 ms of a fast "
      "sine), then for one scored period, or as the first trial with --learn. Only for the "
      "reference, range and loop rate it was "
      "learned for: give the same --reference, --frequency and range (or the same "
      "--reference-file), with the model it was learned with loaded");
  add_request_option(cmd, "--lead-in-max", tr.lead_in_max, t, "lead_in_max_s",
                     "--learned: where the actuator's offset is not the one the drive was "
                     "learned at (its creep after a rest, or after a long run), the lead-in goes "
                     "on while the offset moves toward it, following it, until it is within 5x "
                     "the last trial's rms or stops moving; at most this long [s] (0: the "
                     "shortest lead-in). The result says how long (learning.lead_in_periods) and "
                     "why it ended (learning.lead_in_end)")
      ->needs(learned_opt);
  for (const char* other : {"--periods", "--duration"}) {
    learn_opt->excludes(cmd->get_option(other));
    learned_opt->excludes(cmd->get_option(other));
  }
}

// track --reference-file: a user's trajectory instead of a built-in reference.
void add_track_file_options(CLI::App* cmd, TrackOptions& tr) {
  auto* file_opt =
      cmd->add_option("--reference-file", tr.file,
                      "Follow your own trajectory: a CSV with columns t [s] and yr [um] (an AFM "
                      "raster line, a recorded motion). The daemon resamples it to the loop "
                      "rate and refuses it, naming the first offending row, when it leaves the "
                      "actuator range or moves faster than the slew limit")
          ->check(CLI::ExistingFile);
  for (const char* other : {"--reference", "--frequency", "--periods", "--duration",
                            "--range-fraction", "--min", "--max"}) {
    file_opt->excludes(cmd->get_option(other));
  }
  add_record_columns(cmd, "yr", tr.t_column, tr.yr_column, tr.yr_scale, tr.rate,
                     {"--reference-file: time column [s]", "--reference-file: reference column",
                      "--reference-file: multiply the reference by this (m -> um: 1e6)",
                      "--reference-file: sample rate [Hz] of a file without a time column"});
  add_request_option(cmd, "--approach", tr.approach, common::kTrackUploadedParams, "approach_s",
                     "--reference-file: unscored move from the precondition's end to the first "
                     "value [s], longer when the slew limit needs it");
}

// --learn and --learned into the request; false when neither is given.
bool add_learning(const TrackOptions& tr, nlohmann::json& p) {
  if (!tr.learned.empty()) p["learned"] = tr.learned;
  if (!std::isnan(tr.lead_in_max)) p["lead_in_max_s"] = tr.lead_in_max;
  if (tr.learn > 0) {
    p["learn_trials"] = tr.learn;
    if (!std::isnan(tr.learn_gain)) p["learn_gain"] = tr.learn_gain;
    if (!std::isnan(tr.learn_cutoff)) p["learn_cutoff_hz"] = tr.learn_cutoff;
  }
  return tr.learn > 0 || !tr.learned.empty();
}

// track --reference-file: uploads the trajectory, then starts the run on it.
int track_reference_file(const TrackOptions& tr, cli::RemoteCommand& remote) {
  nlohmann::json p = nlohmann::json::object();
  if (!tr.compensator.empty()) p["compensator"] = tr.compensator;
  if (!std::isnan(tr.precondition)) p["precondition_s"] = tr.precondition;
  if (!std::isnan(tr.approach)) p["approach_s"] = tr.approach;
  add_learning(tr, p);
  add_gains(tr, p);
  if (tr.no_decouple) p["decouple"] = false;
  if (!tr.decoupling.empty()) p["decoupling"] = tr.decoupling;
  // Read once the daemon says whether it drives one axis or a stage (its column per axis).
  remote.reference_file = {tr.file, tr.t_column, tr.yr_column, tr.yr_scale, tr.rate};
  return send_request(remote, "track", p);
}

bool is_stage_reference(const std::string& name) {
  return name == "raster" || name == "lissajous" || name == "spiral";
}

// track on a stage with one of its built-in references.
int track_stage_reference(const TrackOptions& tr, cli::RemoteCommand& remote) {
  nlohmann::json p = {{"reference", tr.reference}};
  if (!tr.frequencies.empty()) p["frequencies_hz"] = tr.frequencies;
  if (tr.duration > 0) p["duration_s"] = tr.duration;
  if (!std::isnan(tr.fraction)) p["range_fraction"] = tr.fraction;
  if (tr.no_decouple) p["decouple"] = false;
  if (!tr.decoupling.empty()) p["decoupling"] = tr.decoupling;
  if (!tr.compensator.empty()) p["compensator"] = tr.compensator;
  if (!std::isnan(tr.precondition)) p["precondition_s"] = tr.precondition;
  add_learning(tr, p);
  add_gains(tr, p);
  return send_request(remote, "track", p);
}

int run_track(const TrackOptions& tr, cli::RemoteCommand& remote) {
  if (!remote.plot_dir.empty() && !remote.wait) {
    std::cerr << "hystbench: error: track --plot needs --wait (the plots are drawn when the run "
                 "ends; or run `hystbench plot LOG` afterwards)\n";
    return 2;
  }
  if (!tr.file.empty()) return track_reference_file(tr, remote);
  if (is_stage_reference(tr.reference)) return track_stage_reference(tr, remote);
  // Only what was given: the daemon fills in its defaults (a stage's differ from one axis's).
  nlohmann::json p = nlohmann::json::object();
  if (!tr.reference.empty()) p["reference"] = tr.reference;
  if (!std::isnan(tr.frequency)) p["frequency_hz"] = tr.frequency;
  if (!tr.frequencies.empty()) p["frequencies_hz"] = tr.frequencies;
  if (tr.no_decouple) p["decouple"] = false;
  if (!tr.decoupling.empty()) p["decoupling"] = tr.decoupling;
  if (add_learning(tr, p)) {
    // a learning run, or a learned drive's (its start-up period and one scored period)
  } else if (tr.duration > 0) {
    p["duration_s"] = tr.duration;
  } else if (!std::isnan(tr.periods)) {
    p["periods"] = tr.periods;
  }
  if (!tr.compensator.empty()) p["compensator"] = tr.compensator;
  if (!std::isnan(tr.precondition)) p["precondition_s"] = tr.precondition;
  add_gains(tr, p);
  if (!std::isnan(tr.min) || !std::isnan(tr.max)) {
    if (!std::isnan(tr.min)) p["min_um"] = tr.min;
    if (!std::isnan(tr.max)) p["max_um"] = tr.max;
  } else if (!std::isnan(tr.fraction)) {
    p["range_fraction"] = tr.fraction;
  }
  return send_request(remote, "track", p);
}

}  // namespace

CliCommand add_track(CLI::App& app, cli::RemoteCommand& remote) {
  auto tr = std::make_shared<TrackOptions>();
  auto* cmd =
      app.add_subcommand("track", "Follow a reference with a compensator and report the error");
  add_track_reference_options(cmd, *tr);
  add_track_learning_options(cmd, *tr);
  add_output_flags(cmd, remote, true);
  cmd->add_option("--plot", remote.plot_dir,
                  "With --wait: write the run's plots (time.png, error.png, loop.png) here "
                  "when it ends, as `hystbench plot` does; with --learn also learning.png "
                  "(the error per trial, and the last trial's error)");
  add_track_file_options(cmd, *tr);
  add_track_gain_options(cmd, *tr);
  return {cmd, [tr, &remote] { return run_track(*tr, remote); }};
}

namespace {

// excite: the drive file and its columns.
struct ExciteOptions {
  std::string input_file;
  cli::RecordColumns columns;
};

}  // namespace

CliCommand add_excite(CLI::App& app, cli::RemoteCommand& remote) {
  auto ex = std::make_shared<ExciteOptions>();
  auto* cmd = app.add_subcommand(
      "excite",
      "Play your own open-loop drive (t [s], u [V]) and log every sample: the run log is a "
      "record that `hystbench fit` and `diagnose` read as it is");
  cmd->add_option("--input-file", ex->input_file,
                  "CSV with columns t [s] and u [V]; refused, naming the first offending row, "
                  "when it leaves [u_min, u_max] or moves faster than the slew limit. On a "
                  "stage, a drive column per axis, named as the axes (t,x,y)")
      ->required()
      ->check(CLI::ExistingFile);
  cli::RecordColumns& drive = ex->columns;
  add_record_columns(
      cmd, "u", drive.t, drive.u, drive.u_scale, drive.rate_hz,
      {"Time column [s]", "Drive column", "Multiply the drive by this (mV -> V: 1e-3)",
       "Sample rate [Hz] of a file without a time column (t = row / rate)"});
  add_output_flags(cmd, remote, true);
  return {cmd, [ex, &remote] {
            const cli::RecordColumns& c = ex->columns;
            // Read once the daemon says whether it drives one axis or a stage (a column each).
            remote.reference_file = {ex->input_file, c.t, c.u, c.u_scale, c.rate_hz, "drive"};
            return send_request(remote, "excite", nlohmann::json::object());
          }};
}

CliCommand add_sweep(CLI::App& app, cli::RemoteCommand& remote) {
  auto sweep = std::make_shared<cli::SweepCommand>();
  auto* cmd = app.add_subcommand(
      "sweep",
      "Track a reference at each of a list of frequencies with each compensator and print one "
      "table of the tracking error (rms / max, % of range): how a stage behaves with frequency.\n"
      "Example: hystbench sweep --frequencies 1,5,10,19,50,100,200 --compensators "
      "none,inverse,inverse+pid --plot sweep/");
  cmd->add_option("--frequencies", sweep->frequencies_hz, "Reference frequencies [Hz]")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--compensators", sweep->compensators,
                  "Compensators, each run at every frequency (none, inverse, "
                  "inverse_multiplicative, inverse+pid, pid)")
      ->delimiter(',')
      ->check(CLI::IsMember({"none", "inverse", "inverse_multiplicative", "inverse+pid", "pid"}))
      ->capture_default_str();
  cmd->add_option("--reference", sweep->reference, "sine, triangle, sawtooth")
      ->check(CLI::IsMember({"sine", "triangle", "sawtooth"}))
      ->capture_default_str();
  cmd->add_option("--periods", sweep->periods, "Periods per run (the first is not scored)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--min-duration", sweep->min_duration_s,
                  "Each run lasts at least this long [s] (more periods at high frequency)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--range-fraction", sweep->range_fraction,
                  "Part of the actuator range the reference spans, centred")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str();
  cmd->add_option("--plot", sweep->plot_dir,
                  "Write sweep.png (error against frequency, log axes) and its data here");
  cmd->add_option("--learn", sweep->learn_trials,
                  "Add a column 'learned': at each frequency a `track --learn N` run from the "
                  "daemon's default compensator (a trial is one period; the frequency moves to "
                  "the loop rate over a whole number of ticks), its last trial's error")
      ->check(CLI::Range(1, 1000));
  cmd->add_flag("--json", sweep->json_output, "Print one JSON object instead of the table");
  return {cmd, [sweep, &remote] {
            sweep->socket_path = remote.socket_path;
            return cli::run_sweep(*sweep, std::cout, std::cerr);
          }};
}

namespace {

// model load: model files (read here, their documents sent) or a model stored in the daemon's
// folder. A stage's files (each naming its axis: identification.stage_axis) go together, keyed
// by axis.
int load_model(const std::vector<std::string>& model_paths, const std::string& stored_model,
               cli::RemoteCommand& remote) {
  if (!stored_model.empty()) return send_request(remote, "model.load", {{"stored", stored_model}});
  if (model_paths.empty()) {
    std::cerr << "hystbench: error: model load: give a model file or --stored NAME\n";
    return 2;
  }
  // The files are read here, with the user's rights, and their documents travel over the
  // socket: the daemon (its own user, its own /tmp and no /home) never opens a client's path.
  std::vector<nlohmann::json> documents;
  try {
    for (const std::string& path : model_paths) {
      documents.push_back(common::read_model_document(path));
    }
  } catch (const std::exception& e) {
    std::cerr << "hystbench: error: " << e.what() << "\n";
    return 1;
  }
  const auto stage_axis = [](const nlohmann::json& d) {
    const nlohmann::json id = d.value("identification", nlohmann::json::object());
    return id.contains("stage") ? id.value("stage_axis", std::string()) : std::string();
  };
  if (documents.size() == 1 && stage_axis(documents.front()).empty()) {
    return send_request(remote, "model.load",
                        {{"model", std::move(documents.front())},
                         {"name", std::filesystem::path(model_paths.front()).filename().string()}});
  }
  nlohmann::json models = nlohmann::json::object();
  std::size_t bytes = 0;
  for (std::size_t i = 0; i < documents.size(); ++i) {
    const std::string axis = stage_axis(documents[i]);
    if (axis.empty() || models.contains(axis)) {
      std::cerr << "hystbench: error: " << model_paths[i]
                << (axis.empty() ? ": not one axis's model of a stage identify (several files "
                                   "load together only as a stage's, one per axis)"
                                 : ": a second model for axis " + axis)
                << "\n";
      return 1;
    }
    bytes += documents[i].dump().size();
    models[axis] = std::move(documents[i]);
  }
  if (bytes > common::kMaxModelFileBytes) {
    std::cerr << "hystbench: error: the stage's model files hold " << bytes
              << " bytes together, more than one request carries (" << common::kMaxModelFileBytes
              << "); copy them into the daemon's model folder and use --stored RUN\n";
    return 1;
  }
  return send_request(remote, "model.load", {{"models", std::move(models)}});
}

// model: get, load, list, delete.
struct ModelOptions {
  std::vector<std::string> model_paths;
  std::string stored_model, deleted_model;
};

}  // namespace

CliCommand add_model(CLI::App& app, cli::RemoteCommand& remote) {
  auto model = std::make_shared<ModelOptions>();
  auto* cmd =
      app.add_subcommand("model", "Show, list, load or delete the models in the daemon's folder");
  cmd->require_subcommand(1);
  const CliCommand get =
      add_plain_request(*cmd, remote, "get", "Print the active model file", "model.get");
  auto* load = cmd->add_subcommand(
      "load",
      "Make a model active: a model file here (read by this command and sent to the daemon, "
      "which keeps a copy in its model folder), or --stored NAME from that folder. On a stage "
      "of several axes, every axis's file of one stage identify (RUN-x.json RUN-y.json)");
  auto* file_opt =
      load->add_option("files", model->model_paths,
                       "Model file (JSON, from fit, diagnose, identify); on a stage, one per axis")
          ->check(CLI::ExistingFile);
  load->add_option("--stored", model->stored_model,
                   "Name of a model in the daemon's model folder (see `hystbench model list`); "
                   "on a stage of several axes, the stage identify's run id (every axis's "
                   "RUN-AXIS.json loads, with the coupling)")
      ->excludes(file_opt);
  add_output_flags(load, remote, false);
  const CliCommand list = add_plain_request(
      *cmd, remote, "list", "The models in the daemon's model folder", "model.list");
  auto* del = cmd->add_subcommand(
      "delete",
      "Delete a model or a learned drive (its JSON and CSV) from the daemon's model folder; "
      "never the active model");
  del->add_option("name", model->deleted_model, "Its name, as `hystbench model list` shows")
      ->required();
  add_output_flags(del, remote, false);
  return {cmd, [=, &remote] {
            if (*get.app) return get.run();
            if (*list.app) return list.run();
            if (*del) return send_request(remote, "model.delete", {{"name", model->deleted_model}});
            return load_model(model->model_paths, model->stored_model, remote);
          }};
}
