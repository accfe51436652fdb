#pragma once
// The subcommands of the `hystbench` CLI: each add_ function registers one command's options on
// `app` and returns the command with what it does once parsed.
#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <span>
#include <string>
#include <string_view>

#include "hystbench/cli/remote/remote_commands.hpp"
#include "hystbench/common/request_schema.hpp"

// A subcommand and what it does once parsed: returns the process's exit code.
struct CliCommand {
  CLI::App* app;
  std::function<int()> run;
};

// The options of a record file of one signal (invert's reference, track's --reference-file,
// excite's drive): --t-column, the signal's column and scale (`signal` "yr" names them
// --yr-column and --yr-scale), and --rate for a file without a time column, in that order. Each
// command words their help itself (`help`, in the same order).
struct RecordColumnsHelp {
  const char* t;
  const char* column;
  const char* scale;
  const char* rate;
};
void add_record_columns(CLI::App* cmd, const std::string& signal, std::string& t_column,
                        std::string& column, double& scale, double& rate_hz,
                        const RecordColumnsHelp& help);

// A number at least `lo` ("FLOAT >= lo" in --help).
CLI::Validator at_least(double lo);

// An option that sets request key `key` of `table` (hystbench/common/run_requests.hpp, the table
// the daemon checks the request with): its help ends with the key's default, and a number's or
// integer's value is checked against the key's range, so that the CLI refuses what the daemon
// would before anything is sent.
template <typename T>
CLI::Option* add_request_option(CLI::App* cmd, const std::string& flag, T& value,
                                std::span<const hystbench::common::ParamSpec> table,
                                std::string_view key, std::string help) {
  namespace common = hystbench::common;
  const common::ParamSpec& spec = common::find_param(table, key);
  const std::string default_words = common::default_text(spec, false);
  if (!default_words.empty()) help += " (default: " + default_words + ")";
  CLI::Option* option = cmd->add_option(flag, value, std::move(help));
  const bool lo = std::isfinite(spec.lo), hi = std::isfinite(spec.hi);
  if (spec.type == common::ParamType::kInteger && lo && hi) {
    option->check(CLI::Range(static_cast<long long>(spec.lo), static_cast<long long>(spec.hi)));
  } else if (spec.type == common::ParamType::kNumber && lo && hi) {
    option->check(CLI::Range(spec.lo, spec.hi));
  } else if (spec.type == common::ParamType::kNumber && lo) {
    option->check(at_least(spec.lo));
  }
  return option;
}

// Offline commands, no daemon needed (offline_subcommands.cpp).
CliCommand add_fit(CLI::App& app);
CliCommand add_simulate(CLI::App& app);
CliCommand add_invert(CLI::App& app);
CliCommand add_diagnose(CLI::App& app);
CliCommand add_convert(CLI::App& app);
CliCommand add_plot(CLI::App& app);

// Bench commands, which talk to hystbenchd (bench_subcommands.cpp). They share `remote`: the
// socket path and the output options --json, --wait and --plot.

// --json, and --wait for a command that starts a run.
void add_output_flags(CLI::App* c, hystbench::cli::RemoteCommand& remote, bool waits);
// Sends the daemon `cmd` with `params`; returns the exit code of run_remote.
int send_request(hystbench::cli::RemoteCommand& remote, const std::string& cmd,
                 nlohmann::json params);

// A command that sends the daemon one request without parameters (status, stop, config ...).
CliCommand add_plain_request(CLI::App& parent, hystbench::cli::RemoteCommand& remote,
                             const std::string& name, const std::string& description,
                             const std::string& request);
CliCommand add_identify(CLI::App& app, hystbench::cli::RemoteCommand& remote);
CliCommand add_track(CLI::App& app, hystbench::cli::RemoteCommand& remote);
CliCommand add_excite(CLI::App& app, hystbench::cli::RemoteCommand& remote);
CliCommand add_sweep(CLI::App& app, hystbench::cli::RemoteCommand& remote);
CliCommand add_model(CLI::App& app, hystbench::cli::RemoteCommand& remote);
// The stage's frequency responses and the feedback designed on them (feedback_subcommands.cpp).
CliCommand add_frf(CLI::App& app, hystbench::cli::RemoteCommand& remote);
CliCommand add_tune(CLI::App& app, hystbench::cli::RemoteCommand& remote);
