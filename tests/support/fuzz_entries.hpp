#pragma once
// The fuzzed entry points, shared by the libFuzzer targets (fuzz/*_fuzz.cpp) and the regression
// test that replays every committed crasher (tests/daemon/fuzz_regressions_test.cpp).
// Each entry takes arbitrary bytes and must neither crash, hang nor leak; the documented
// exceptions of a parser are the expected outcome for bad input and are swallowed here.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "../../daemon/src/details/json_lines.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/daemon/bench.hpp"
#include "hystbench/daemon/config.hpp"
#include "hystbench/daemon/daemon_settings.hpp"
#include "hystbench/daemon/data_table.hpp"

namespace hystbench::fuzz {

/// One request line through the socket protocol parser and, when it parses, the bench's
/// dispatcher (a loopback bench whose loop is not started: runs are accepted but never tick),
/// then the reply serialisation, exactly as SocketServer::handle_line and hystbenchd do.
inline void request_line(const std::uint8_t* data, std::size_t size) {
  static daemon::Bench* bench = [] {
    const auto dir =
        std::filesystem::temp_directory_path() / ("hystbench_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    daemon::BenchSettings s;
    s.log_dir = (dir / "logs").string();
    s.model_dir = (dir / "models").string();
    s.log_ring_capacity = 1024;
    return new daemon::Bench(s);  // never destroyed: shared by every input
  }();
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  if (line.find('\n') != std::string_view::npos) return;  // the server splits at '\n'
  daemon::Request request;
  daemon::details::ProtocolError error;
  if (!daemon::details::parse_request(line, request, error)) {
    (void)daemon::details::error_line(error.id, error.code, error.message);
    return;
  }
  // model.load carries the model document (kept in the bench's model folder, a temporary
  // folder here) or names a model in that folder; it never opens a path a request names, so
  // the fuzzer drives it too.
  daemon::Reply reply;
  try {
    reply = daemon::Reply::success(bench->handle(request.cmd, request.params));
  } catch (const daemon::CommandError& e) {
    reply = daemon::Reply::failure(e.code(), e.what());
  } catch (const std::exception& e) {
    reply = daemon::Reply::failure("internal", e.what());
  }
  (void)daemon::details::reply_line(request.id, reply);
}

/// TOML configuration text through the loader and the mapping onto the bench settings.
inline void config_text(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const auto config = daemon::parse_config(text, "fuzz.toml");
    (void)daemon::to_json(config).dump();
    (void)daemon::bench_settings_from(config);
  } catch (const daemon::ConfigError&) {
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

/// CSV text through the data-table reader (DataFileError is its documented error).
inline void csv_text(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto table = daemon::DataTable::parse_csv(text, "fuzz.csv");
    for (const auto& name : table.names()) (void)table.column(name);
    if (table.has("t")) {
      table.require_increasing("t");
      (void)table.sample_period();
    }
  } catch (const daemon::DataFileError&) {
  }
}

}  // namespace hystbench::fuzz
