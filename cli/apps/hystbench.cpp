// hystbench: the bench's command-line tool.
//   Offline (no daemon needed): fit, simulate, invert, diagnose on CSV files; convert .npy to CSV.
//   Bench (talks to hystbenchd over its Unix socket): status, identify, track, excite, sweep,
//   stop, abort, reset, model, config.
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "hystbench/cli/remote/remote_commands.hpp"
#include "hystbench/common/run_main.hpp"
#include "subcommands.hpp"

namespace cli = hystbench::cli;

namespace {

int run(int argc, char** argv) {
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

  std::vector<CliCommand> commands;
  commands.push_back(add_fit(app));
  commands.push_back(add_simulate(app));
  commands.push_back(add_invert(app));
  commands.push_back(add_diagnose(app));
  commands.push_back(add_convert(app));

  // The bench commands' connection and output settings, shared by all of them.
  cli::RemoteCommand remote;
  remote.socket_path = cli::default_socket_path();
  app.add_option("--socket", remote.socket_path,
                 "hystbenchd socket (default $HYSTBENCH_SOCKET or /run/hystbench/hystbench.sock)");
  commands.push_back(add_plain_request(
      app, remote, "status", "State, active run, model, loop timing, last result", "status"));
  commands.push_back(add_plain_request(
      app, remote, "runs",
      "The last 200 runs, newest first, also from before a restart: id, kind, end, figure,\n"
      "log (JSON)",
      "runs"));
  commands.push_back(add_identify(app, remote));
  commands.push_back(add_track(app, remote));
  commands.push_back(add_excite(app, remote));
  commands.push_back(add_frf(app, remote));
  commands.push_back(add_tune(app, remote));
  commands.push_back(add_plot(app));
  commands.push_back(add_sweep(app, remote));
  commands.push_back(add_plain_request(app, remote, "stop",
                                       "End the active run normally (its result is kept)", "stop"));
  commands.push_back(add_plain_request(app, remote, "abort",
                                       "Safe output now; the active run ends as aborted", "abort"));
  commands.push_back(
      add_plain_request(app, remote, "reset", "Leave FAULT after the cause is fixed", "reset"));
  commands.push_back(add_model(app, remote));
  commands.push_back(add_plain_request(app, remote, "config",
                                       "Print the daemon's effective configuration", "config.get"));

  CLI11_PARSE(app, argc, argv);

  for (const CliCommand& command : commands) {
    if (*command.app) return command.run();
  }
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  return hystbench::common::run_main("hystbench", run, argc, argv);
}
