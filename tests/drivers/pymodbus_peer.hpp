#pragma once
// Test helper: the independent Modbus TCP server of tests/drivers/modbus_peer.py (Debian's
// python3-pymodbus) on 127.0.0.1 and a free port, and REQUIRE_PYMODBUS() to skip, naming the
// package, when it is not installed.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "peer_process.hpp"

namespace hystbench::test {

inline constexpr const char* kPython =
    "/usr/bin/python3";  // Debian's, where python3-pymodbus lives

inline bool pymodbus_available() {
  static const bool ok =
      ::access(kPython, X_OK) == 0 &&
      run_program({kPython, "-c", "import pymodbus.server.async_io"}, std::chrono::seconds(20))
              .first == 0;
  return ok;
}

inline std::string peer_script() {
  return (std::filesystem::path(HYSTBENCH_SOURCE_DIR) / "tests/drivers/modbus_peer.py").string();
}

/// The pymodbus peer on a free port; `port` is 0 until it listens.
struct PymodbusPeer {
  explicit PymodbusPeer(std::vector<std::string> args) {
    std::vector<std::string> argv{kPython, peer_script()};
    argv.insert(argv.end(), args.begin(), args.end());
    proc = std::make_unique<PeerProcess>(argv);
    if (auto line = proc->wait_for("port ", std::chrono::seconds(20)))
      port = std::stoi(line->substr(5));
  }
  /// The next register write the peer logged whose values contain `value`.
  nlohmann::json wait_write(int value,
                            std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < until) {
      auto line = proc->read_line(std::chrono::duration_cast<std::chrono::milliseconds>(
          until - std::chrono::steady_clock::now()));
      if (!line) break;
      if (line->empty() || (*line)[0] != '{') continue;
      const nlohmann::json j = nlohmann::json::parse(*line);
      for (const auto& v : j["values"]) {
        if (v == value) return j;
      }
    }
    return nlohmann::json();
  }
  /// Sends `sig` to the server (modbus_peer.py --plant: SIGUSR1 freezes the measurement,
  /// SIGUSR2 thaws it; SIGSTOP / SIGCONT stop and resume answering).
  void signal(int sig) const { ::kill(proc->pid(), sig); }
  std::unique_ptr<PeerProcess> proc;
  int port = 0;
};

}  // namespace hystbench::test

#define REQUIRE_PYMODBUS()                                                                     \
  if (!::hystbench::test::pymodbus_available())                                                \
  GTEST_SKIP() << "python3-pymodbus is not installed (scripts/deps.sh test installs it): the " \
                  "independent Modbus server peer is missing"
