// hystbenchd: the bench daemon. Runs the fixed-rate loop against the configured driver, logs
// every sample, answers JSON-lines commands on a Unix socket. See README and `--help`.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <iostream>

#include "hystbench/daemon/bench.hpp"
#include "hystbench/daemon/config.hpp"
#include "hystbench/daemon/daemon_settings.hpp"
#include "hystbench/daemon/socket_server.hpp"

namespace hd = hystbench::daemon;

int main(int argc, char** argv) {
  CLI::App app{
      "hystbenchd - hystbench bench daemon: fixed-rate loop, every-sample logs, command socket\n"
      "\n"
      "Without --config it runs on the built-in defaults: the loopback driver (a simulated\n"
      "150 V / 45 um piezo stack) at 10 kHz. Script it with `hystbench` (see `hystbench --help`).\n"
      "SIGTERM or SIGINT: safe output, the active run ends, its log is closed, exit 0."};
  std::string config_path, socket_path, log_dir, model_dir, clock;
  bool check_only = false;
  app.add_option("-c,--config", config_path, "TOML configuration file (see config/*.toml)")
      ->check(CLI::ExistingFile);
  app.add_option("--socket", socket_path, "Command socket path (overrides daemon.socket_path)");
  app.add_option("--log-dir", log_dir, "Run log folder (overrides daemon.log_dir)");
  app.add_option("--model-dir", model_dir, "Model folder (overrides daemon.model_dir)");
  app.add_option("--clock", clock,
                 "Loop clock (overrides loop.clock): wall, or simulated (loopback driver only:\n"
                 "virtual time, runs tick as fast as they compute, idle ticks stay paced)")
      ->check(CLI::IsMember({"wall", "simulated"}));
  app.add_flag("--check-config", check_only, "Validate the configuration, print it and exit");
  app.set_version_flag("--version", std::string(HYSTBENCH_VERSION));
  CLI11_PARSE(app, argc, argv);

  hd::DaemonConfig config;
  try {
    if (!config_path.empty()) config = hd::load_config(config_path);
  } catch (const hd::ConfigError& e) {
    std::cerr << "hystbenchd: configuration error: " << e.what() << "\n";
    return 2;
  }
  if (!socket_path.empty()) config.daemon.socket_path = socket_path;
  if (!log_dir.empty()) config.daemon.log_dir = log_dir;
  if (!model_dir.empty()) config.daemon.model_dir = model_dir;
  if (!clock.empty()) {
    if (const std::string why = hd::clock_conflict(clock, config.driver.type); !why.empty()) {
      std::cerr << "hystbenchd: configuration error: --clock: " << why << "\n";
      return 2;
    }
    config.loop.clock = clock;
  }
  spdlog::set_level(spdlog::level::from_str(config.daemon.log_level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

  hd::BenchSettings settings;
  try {
    settings = hd::bench_settings_from(config);
  } catch (const hd::ConfigError& e) {
    std::cerr << "hystbenchd: configuration error: " << e.what() << "\n";
    return 2;
  }
  if (check_only) {
    std::cout << settings.config_json.dump(2) << "\n";
    return 0;
  }

  // Signals are taken synchronously by the main thread; every thread started below inherits
  // the blocked mask, so none of them is interrupted.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);

  std::unique_ptr<hd::Bench> bench;
  try {
    bench = std::make_unique<hd::Bench>(settings);
  } catch (const std::exception& e) {
    spdlog::critical("cannot start the driver '{}': {}", config.driver.type, e.what());
    return 1;
  }
  const hd::RealtimeReport rt = bench->start();
  hd::RealtimeOptions requested = settings.loop.realtime;
  if (rt.degraded()) {
    spdlog::warn("{} -- running degraded (grant CAP_SYS_NICE and CAP_IPC_LOCK, see README)",
                 rt.summary(requested));
  } else {
    spdlog::info("{}", rt.summary(requested));
  }

  hd::SocketServer server(
      {config.daemon.socket_path},
      [&bench](const hd::Request& req) -> hd::Reply {
        try {
          spdlog::debug("client {}: {}", req.client, req.cmd);
          return hd::Reply::success(bench->handle(req.cmd, req.params, req.client));
        } catch (const hd::CommandError& e) {
          spdlog::info("client {}: {} refused: {}", req.client, req.cmd, e.what());
          return hd::Reply::failure(e.code(), e.what(), e.detail());
        } catch (const std::exception& e) {
          spdlog::error("client {}: {} failed: {}", req.client, req.cmd, e.what());
          return hd::Reply::failure("internal", e.what());
        }
      },
      // A connection that goes away mid-upload leaves nothing behind.
      [&bench](std::uint64_t client) { bench->client_closed(client); });
  try {
    server.start();
  } catch (const std::exception& e) {
    spdlog::critical("command socket: {}", e.what());
    bench->shutdown();
    return 1;
  }
  bench->set_event_sink([&server](const nlohmann::json& event) {
    if (event.value("event", "") == "run.finished") {
      const auto& r = event["result"];
      spdlog::info("run {} {}{}{}", r.value("run_id", "?"), r.value("end", "?"),
                   r.value("reason", std::string()).empty() ? "" : ": ",
                   r.value("reason", std::string()));
    }
    server.broadcast_event(event);
  });
  spdlog::info("hystbenchd {} ready: driver {}, {} Hz, {} clock, socket {}, logs {}",
               HYSTBENCH_VERSION, config.driver.type, config.loop.rate_hz, config.loop.clock,
               config.daemon.socket_path, config.daemon.log_dir);
  sd_notifyf(0, "READY=1\nSTATUS=driver %s, %.0f Hz", config.driver.type.c_str(),
             config.loop.rate_hz);

  std::uint64_t watchdog_usec = 0;
  const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0 && watchdog_usec > 0;
  const auto interval =
      watchdog ? std::chrono::microseconds(watchdog_usec / 2) : std::chrono::microseconds(1000000);
  int received = 0;
  while (received == 0) {
    const auto secs = std::chrono::duration_cast<std::chrono::seconds>(interval);
    timespec timeout{static_cast<time_t>(secs.count()),
                     static_cast<long>((interval - secs).count() * 1000)};
    const int sig = sigtimedwait(&signals, nullptr, &timeout);
    if (sig > 0 && sig != SIGHUP) {
      received = sig;
    } else if (sig == SIGHUP) {
      spdlog::info("SIGHUP ignored (restart the service to apply a new configuration)");
    } else if (watchdog && bench->loop_advanced()) {
      sd_notify(0, "WATCHDOG=1");
    }
  }
  spdlog::info("{} received: safe output, ending the run, closing the log", strsignal(received));
  sd_notify(0, "STOPPING=1");
  bench->shutdown();
  server.stop();
  spdlog::info("hystbenchd stopped");
  return 0;
}
