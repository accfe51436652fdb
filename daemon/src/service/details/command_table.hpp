#pragma once
// The bench's socket commands, one row each: name, parameters (key, type, range) and handler.
// Bench::handle() finds the row, checks the request against it (details/request_params.hpp:
// an unknown key, a wrong type or a value out of range is bad_params naming the key) and only
// then calls the handler. Not real-time safe.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>

#include "hystbench/daemon/service/bench.hpp"
#include "runs/details/request_params.hpp"

namespace hystbench::daemon::details {

struct Command {
  const char* name;
  /// The row applies when the request holds this key; null = otherwise (a command may have
  /// two rows, e.g. track with a built-in or an uploaded reference).
  const char* when_key;
  std::span<const ParamSpec> params;
  nlohmann::json (*handle)(Bench& bench, const RequestParams& request, std::uint64_t client);
  /// The command only reads: it changes neither the bench nor its models (a read-only front
  /// end, such as the live view without control, answers it).
  bool reads_only = false;
};

/// Every command, in the order unknown_command lists them.
std::span<const Command> bench_commands();

/// The row for `name` and these params; throws CommandError unknown_command listing every name.
const Command& find_command(const std::string& name, const nlohmann::json& params);

/// Whether command `name` only reads (every row of it does); false for an unknown name.
bool command_reads_only(const std::string& name);

}  // namespace hystbench::daemon::details
