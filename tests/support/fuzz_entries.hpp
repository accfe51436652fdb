#pragma once
// The fuzzed entry points, shared by the libFuzzer targets (fuzz/*_fuzz.cpp) and the regression
// test that replays every committed crasher (tests/daemon/fuzz_regressions_test.cpp).
// Each entry takes arbitrary bytes and must neither crash, hang nor leak; the documented
// exceptions of a parser are the expected outcome for bad input and are swallowed here.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <system_error>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/config/daemon_settings.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "service/details/json_lines.hpp"

namespace hystbench::fuzz {

/// Request lines (the input split at '\n', as the server splits a connection's bytes) through
/// the socket protocol parser and, when one parses, the bench's dispatcher (a loopback bench
/// whose loop is not started: runs are accepted but never tick), then the reply serialisation,
/// exactly as SocketServer::handle_line and hystbenchd do. The lines come from one connection
/// that closes at the end, so upload sequences (begin, chunks, a run that uses the upload,
/// cancel) are fuzzed together with the disconnect that discards them.
inline void request_line(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hystbench_fuzz_" + std::to_string(::getpid()));
  static daemon::Bench* bench = [] {
    std::filesystem::create_directories(dir);
    // The bench is never destroyed (its loop is never started); its folder goes at exit.
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    });
    daemon::BenchSettings s;
    s.log_dir = (dir / "logs").string();
    s.model_dir = (dir / "models").string();
    s.log_ring_capacity = 1024;
    return new daemon::Bench(s);  // never destroyed: shared by every input
  }();
  static std::uint64_t client = 0;
  ++client;
  std::string_view input(reinterpret_cast<const char*>(data), size);
  for (;;) {
    const std::size_t end = input.find('\n');
    const std::string_view line = input.substr(0, end);
    daemon::Request request;
    daemon::details::ProtocolError error;
    if (!daemon::details::parse_request(line, request, error)) {
      (void)daemon::details::error_line(error.id, error.code, error.message);
    } else {
      // model.load carries the model document (kept in the bench's model folder, a temporary
      // folder here) or names a model in that folder; it never opens a path a request names,
      // so the fuzzer drives it too.
      daemon::Reply reply;
      try {
        reply = daemon::Reply::success(bench->handle(request.cmd, request.params, client));
      } catch (const common::CommandError& e) {
        reply = daemon::Reply::failure(e.code(), e.what(), e.detail());
      } catch (const std::exception& e) {
        reply = daemon::Reply::failure("internal", e.what());
      }
      (void)daemon::details::reply_line(request.id, reply);
    }
    if (end == std::string_view::npos) break;
    input.remove_prefix(end + 1);
  }
  bench->client_closed(client);
}

/// TOML configuration text through the loader and the mapping onto the bench settings; true
/// when accepted, false on its documented error (ConfigError).
inline bool config_text(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const auto config = daemon::parse_config(text, "fuzz.toml");
    (void)daemon::to_json(config).dump();
    (void)daemon::bench_settings_from(config);
    return true;
  } catch (const daemon::ConfigError&) {
    return false;
  }
}

/// Model-file text through the loader (ModelFileError is its documented error), then what
/// model.load does with an accepted model.
inline void model_file_text(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto file = compensation::parse_model_file(text);
    (void)file.model.hysteresis().invertibility();
    (void)compensation::to_json(file).dump();
  } catch (const compensation::ModelFileError&) {
  }
}

/// CSV text through the data-table reader; true when accepted, false on its documented error
/// (DataFileError).
inline bool csv_text(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto table = cli::DataTable::parse_csv(text, "fuzz.csv");
    for (const auto& name : table.names()) (void)table.column(name);
    if (table.has("t")) {
      table.require_increasing("t");
      (void)table.sample_period();
    }
    return true;
  } catch (const cli::DataFileError&) {
    return false;
  }
}

}  // namespace hystbench::fuzz
