// The feedback's commands of the `hystbench` CLI: frf (the stage's frequency responses,
// measured in place) and tune (the loop designed on them, nothing run). They talk to hystbenchd
// over its socket.
#include <cmath>
#include <iostream>
#include <memory>
#include <string>

#include "hystbench/common/run_requests.hpp"
#include "subcommands.hpp"

namespace cli = hystbench::cli;
namespace common = hystbench::common;

namespace {

struct FrfOptions {
  double amplitude = NAN;
  int periods = 0;
};

struct TuneOptions {
  std::string compensator;
  double kp = NAN, ki = NAN, kd = NAN;
};

}  // namespace

CliCommand add_frf(CLI::App& app, cli::RemoteCommand& remote) {
  auto o = std::make_shared<FrfOptions>();
  auto* cmd = app.add_subcommand(
      "frf",
      "Measure the stage's frequency response in place: after a sweep to both drive limits, "
      "small multisines at a quarter, half and three quarters of the drive span (2 % of it) and "
      "a larger one at half (8 %), each averaged over 4 periods, every line to 0.45 of the loop "
      "rate with its noise and coherence; then the stage while it moves, ramps up and down "
      "across the middle of the span carrying a small sine at a fiftieth of the loop rate: a "
      "rate law acts only then, and one direction's ramps lagging the other's is the zero it "
      "puts on the loop (about 4 s at 10 kHz, 14 s at 1 kHz). The bench and the active model "
      "keep it (its file is saved again): the feedback of inverse+pid and pid is designed on it. "
      "The result gives the modes found, the zero found while moving, how far the gain and the "
      "first mode moved since the last measurement, and the loop designed now. identify "
      "measures it too.\n"
      "Example: hystbench frf --wait --plot frf/");
  add_request_option(cmd, "--amplitude", o->amplitude, common::kFrfParams, "amplitude",
                     "Peak of the small multisines, a fraction of the drive span (the larger one "
                     "is 4x)");
  add_request_option(cmd, "--periods", o->periods, common::kFrfParams, "periods",
                     "Periods averaged per condition");
  add_output_flags(cmd, remote, true);
  cmd->add_option("--plot", remote.plot_dir,
                  "With --wait: write response.png (magnitude, phase and coherence of each "
                  "measured response) here");
  return {cmd, [o, &remote] {
            if (!remote.plot_dir.empty() && !remote.wait) {
              std::cerr << "hystbench: error: frf --plot needs --wait\n";
              return 2;
            }
            nlohmann::json p = nlohmann::json::object();
            if (!std::isnan(o->amplitude)) p["amplitude"] = o->amplitude;
            if (o->periods > 0) p["periods"] = o->periods;
            return send_request(remote, "frf", p);
          }};
}

CliCommand add_tune(CLI::App& app, cli::RemoteCommand& remote) {
  auto o = std::make_shared<TuneOptions>();
  auto* cmd = app.add_subcommand(
      "tune",
      "Print the feedback a track run would get, without running anything: the loop designed "
      "on the stage's measured frequency responses (as the feedback sees them through the "
      "feedforward), its parts, crossover and bandwidths, its margins on every response "
      "against the targets ([pid] gain_margin_db, phase_margin_deg, peak_sensitivity_db) and "
      "what limited it; or with --kp/--ki/--kd the margins of those gains (a track refuses "
      "gains that break a target unless --force-gains). On a stage of several axes: each "
      "axis's loop, and the loops checked together through the coupling (lowered together "
      "where they would not hold), as a track runs them; --plot writes each axis's pictures "
      "in DIR/AXIS.\n"
      "Example: hystbench tune --plot tune/");
  add_request_option(cmd, "--compensator", o->compensator, common::kTuneParams, "compensator",
                     "inverse+pid or pid")
      ->check(CLI::IsMember({"inverse+pid", "pid"}));
  add_request_option(cmd, "--kp", o->kp, common::kTuneParams, "kp",
                     "Proportional gain to check [V/um]");
  add_request_option(cmd, "--ki", o->ki, common::kTuneParams, "ki",
                     "Integral gain to check [V/(um s)]");
  add_request_option(cmd, "--kd", o->kd, common::kTuneParams, "kd",
                     "Derivative gain to check [V s/um]");
  add_output_flags(cmd, remote, false);
  cmd->add_option("--plot", remote.plot_dir,
                  "Write loop-bode.png (|L| and arg L with the crossover and the phase-margin "
                  "line), nyquist.png (L, the -1 point and the peak-|S| circle) and "
                  "sensitivity.png (|S| and |T|) here");
  return {cmd, [o, &remote] {
            nlohmann::json p = nlohmann::json::object();
            if (!o->compensator.empty()) p["compensator"] = o->compensator;
            if (!std::isnan(o->kp)) p["kp"] = o->kp;
            if (!std::isnan(o->ki)) p["ki"] = o->ki;
            if (!std::isnan(o->kd)) p["kd"] = o->kd;
            return send_request(remote, "tune", p);
          }};
}
