// hystbenchd: the bench daemon. Runs the fixed-rate loop against the configured driver, logs
// every sample, answers JSON-lines commands on a Unix socket. See README and `--help`.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <iostream>
#include <optional>

#include "hystbench/common/run_main.hpp"
#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/config/daemon_settings.hpp"
#include "hystbench/daemon/http/access_token.hpp"
#include "hystbench/daemon/http/scope_feed.hpp"
#include "hystbench/daemon/http/web_view.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "hystbench/daemon/service/socket_server.hpp"

namespace hd = hystbench::daemon;
namespace common = hystbench::common;

namespace {

// The command line: a configuration file and the settings that override it.
struct DaemonOptions {
  std::string config_path, socket_path, log_dir, model_dir, clock, http;
  bool check_only = false;
};

void add_daemon_options(CLI::App& app, DaemonOptions& options) {
  app.add_option("-c,--config", options.config_path, "TOML configuration file (see config/*.toml)")
      ->check(CLI::ExistingFile);
  app.add_option("--socket", options.socket_path,
                 "Command socket path (overrides daemon.socket_path)");
  app.add_option("--log-dir", options.log_dir, "Run log folder (overrides daemon.log_dir)");
  app.add_option("--model-dir", options.model_dir, "Model folder (overrides daemon.model_dir)");
  app.add_option("--clock", options.clock,
                 "Loop clock (overrides loop.clock): wall, or simulated (loopback driver only:\n"
                 "virtual time, runs tick as fast as they compute, idle ticks stay paced)")
      ->check(CLI::IsMember({"wall", "simulated"}));
  app.add_option("--http", options.http,
                 "Serve the live view in a browser on HOST:PORT (overrides http.listen), e.g.\n"
                 "127.0.0.1:8080; port 0 picks a free one (status shows it). Read-only unless\n"
                 "http.control = true (docs/reference/web-view.md)");
  app.add_flag("--check-config", options.check_only,
               "Validate the configuration, print it and exit");
  app.set_version_flag("--version", std::string(HYSTBENCH_VERSION));
}

// The configuration file's (the built-in defaults without one) with the command line's
// overrides; nullopt after printing why it is not valid.
std::optional<hd::DaemonConfig> load_daemon_config(const DaemonOptions& options) {
  hd::DaemonConfig config;
  try {
    if (!options.config_path.empty()) config = hd::load_config(options.config_path);
  } catch (const hd::ConfigError& e) {
    std::cerr << "hystbenchd: configuration error: " << e.what() << "\n";
    return std::nullopt;
  }
  if (!options.socket_path.empty()) config.daemon.socket_path = options.socket_path;
  if (!options.log_dir.empty()) config.daemon.log_dir = options.log_dir;
  if (!options.model_dir.empty()) config.daemon.model_dir = options.model_dir;
  if (!options.clock.empty()) {
    if (const std::string why = hd::clock_conflict(options.clock, config.driver.type);
        !why.empty()) {
      std::cerr << "hystbenchd: configuration error: --clock: " << why << "\n";
      return std::nullopt;
    }
    config.loop.clock = options.clock;
  }
  if (!options.http.empty()) {
    if (const hd::ListenAddress a = hd::parse_listen_address(options.http); !a.error.empty()) {
      std::cerr << "hystbenchd: configuration error: --http: " << a.error << "\n";
      return std::nullopt;
    }
    config.http.listen = options.http;
  }
  return config;
}

// Blocks SIGTERM, SIGINT and SIGHUP, which the main thread then takes synchronously; every
// thread started afterwards inherits the blocked mask, so none of them is interrupted.
sigset_t block_stop_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);
  return signals;
}

// Starts the driver and the loop and logs the realtime setup; nullptr after logging why the
// driver cannot start.
std::unique_ptr<hd::Bench> start_bench(const hd::DaemonConfig& config,
                                       const hd::BenchSettings& settings) {
  std::unique_ptr<hd::Bench> bench;
  try {
    bench = std::make_unique<hd::Bench>(settings);
  } catch (const std::exception& e) {
    spdlog::critical("cannot start the driver '{}': {}", config.driver.type, e.what());
    return nullptr;
  }
  const hd::RealtimeReport rt = bench->start();
  hd::RealtimeOptions requested = settings.loop.realtime;
  if (rt.degraded()) {
    spdlog::warn("{} -- running degraded (grant CAP_SYS_NICE and CAP_IPC_LOCK, see README)",
                 rt.summary(requested));
  } else {
    spdlog::info("{}", rt.summary(requested));
  }
  return bench;
}

// Answers a client's request with the bench's reply, a refusal or an internal failure.
hd::SocketServer::Dispatcher bench_dispatcher(hd::Bench& bench) {
  return [&bench](const hd::Request& req) -> hd::Reply {
    try {
      spdlog::debug("client {}: {}", req.client, req.cmd);
      return hd::Reply::success(bench.handle(req.cmd, req.params, req.client));
    } catch (const common::CommandError& e) {
      spdlog::info("client {}: {} refused: {}", req.client, req.cmd, e.what());
      return hd::Reply::failure(e.code(), e.what(), e.detail());
    } catch (const std::exception& e) {
      spdlog::error("client {}: {} failed: {}", req.client, req.cmd, e.what());
      return hd::Reply::failure("internal", e.what());
    }
  };
}

// Logs every finished run and sends every event of the bench to the socket's clients and the
// live view's streams.
void forward_events(hd::Bench& bench, hd::SocketServer& server, hd::WebView* view) {
  bench.set_event_sink([&server, view](const nlohmann::json& event) {
    if (event.value("event", "") == "run.finished") {
      const auto& r = event["result"];
      spdlog::info("run {} {}{}{}", r.value("run_id", "?"), r.value("end", "?"),
                   r.value("reason", std::string()).empty() ? "" : ": ",
                   r.value("reason", std::string()));
    }
    server.broadcast_event(event);
    if (view != nullptr) view->publish(event);
  });
}

// Waits for SIGTERM or SIGINT and returns it; feeds systemd's watchdog meanwhile while the loop
// advances, and ignores SIGHUP.
int wait_for_stop_signal(const sigset_t& signals, hd::Bench& bench) {
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
    } else if (watchdog && bench.loop_advanced()) {
      sd_notify(0, "WATCHDOG=1");
    }
  }
  return received;
}

// The live view ([http]): the loop's scope tap, the feed that drains it and the HTTP server.
// All null while http.listen is empty.
struct LiveView {
  std::unique_ptr<hd::ScopeTap> tap;
  std::unique_ptr<hd::ScopeFeed> feed;
  std::unique_ptr<hd::WebView> view;
};

// The tap the loop offers its samples to, when the view is on (before the bench starts).
std::unique_ptr<hd::ScopeTap> make_scope_tap(const hd::DaemonConfig& config) {
  if (config.http.listen.empty()) return nullptr;
  const std::uint32_t decimation =
      hd::ScopeTap::decimation_for(config.loop.rate_hz, config.http.scope_rate_hz);
  // Two seconds of scope samples: the feed drains it every 10 ms.
  return std::make_unique<hd::ScopeTap>(decimation,
                                        static_cast<std::size_t>(2 * config.http.scope_rate_hz));
}

// Starts the feed and the HTTP server; false after logging why the address cannot be served.
bool start_live_view(const hd::DaemonConfig& config, const hd::BenchSettings& settings,
                     const std::string& token, hd::Bench& bench, LiveView& live) {
  if (!live.tap) return true;
  std::vector<std::string> axes =
      settings.axes.empty() ? std::vector<std::string>{""} : settings.axes;
  hd::ScopeFeedOptions feed;
  feed.loop_rate_hz = config.loop.rate_hz;
  feed.axes = axes;
  live.feed = std::make_unique<hd::ScopeFeed>(*live.tap, feed);
  const hd::ListenAddress address = hd::parse_listen_address(config.http.listen);
  hd::WebViewOptions options;
  options.host = address.host;
  options.port = address.port;
  options.control = config.http.control;
  options.token = token;
  options.max_clients = static_cast<std::size_t>(config.http.max_clients);
  options.log_dir = config.daemon.log_dir;
  options.driver = config.driver.type;
  options.rate_hz = config.loop.rate_hz;
  options.scope_rate_hz = config.loop.rate_hz / live.tap->decimation();
  options.axes = axes;
  try {
    live.view = std::make_unique<hd::WebView>(options, bench, live.feed.get());
    live.feed->start();
    live.view->start();
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return false;
  }
  bench.set_web_view_status({{"address", live.view->address()}, {"control", options.control}});
  spdlog::info("live view on http://{}/ ({}; scope {} samples/s)", live.view->address(),
               options.control ? "runs may be started from it with the token" : "read-only",
               options.scope_rate_hz);
  return true;
}

// Runs the bench, its command socket and the live view until a stop signal; returns the exit
// code.
int run_daemon(const hd::DaemonConfig& config, hd::BenchSettings settings, const std::string& token,
               const sigset_t& signals) {
  LiveView live;  // outlives the bench: the loop offers samples to its tap
  live.tap = make_scope_tap(config);
  settings.loop.scope = live.tap.get();
  std::unique_ptr<hd::Bench> bench = start_bench(config, settings);
  if (!bench) return 1;
  hd::SocketServer server({config.daemon.socket_path}, bench_dispatcher(*bench),
                          // A connection that goes away mid-upload leaves nothing behind.
                          [&bench](std::uint64_t client) { bench->client_closed(client); });
  try {
    server.start();
  } catch (const std::exception& e) {
    spdlog::critical("command socket: {}", e.what());
    bench->shutdown();
    return 1;
  }
  if (!start_live_view(config, settings, token, *bench, live)) {
    bench->shutdown();
    return 1;
  }
  forward_events(*bench, server, live.view.get());
  spdlog::info("hystbenchd {} ready: driver {}, {} Hz, {} clock, socket {}, logs {}",
               HYSTBENCH_VERSION, config.driver.type, config.loop.rate_hz, config.loop.clock,
               config.daemon.socket_path, config.daemon.log_dir);
  sd_notifyf(0, "READY=1\nSTATUS=driver %s, %.0f Hz", config.driver.type.c_str(),
             config.loop.rate_hz);

  const int received = wait_for_stop_signal(signals, *bench);
  spdlog::info("{} received: safe output, ending the run, closing the log", strsignal(received));
  sd_notify(0, "STOPPING=1");
  if (live.view) live.view->stop();
  bench->shutdown();
  server.stop();
  spdlog::info("hystbenchd stopped");
  return 0;
}

// The live view's token, when it controls runs; nullopt after printing why it cannot be read.
std::optional<std::string> live_view_token(const hd::DaemonConfig& config) {
  if (config.http.listen.empty() || !config.http.control) return std::string();
  try {
    return hd::read_access_token(hd::access_token_path(config.http.token_file));
  } catch (const hd::AccessTokenError& e) {
    std::cerr << "hystbenchd: configuration error: http.control: " << e.what() << "\n";
    return std::nullopt;
  }
}

int run(int argc, char** argv) {
  CLI::App app{
      "hystbenchd - hystbench bench daemon: fixed-rate loop, every-sample logs, command socket\n"
      "\n"
      "Without --config it runs on the built-in defaults: the loopback driver (a simulated\n"
      "150 V / 45 um piezo stack) at 10 kHz. Script it with `hystbench` (see `hystbench --help`).\n"
      "SIGTERM or SIGINT: safe output, the active run ends, its log is closed, exit 0."};
  DaemonOptions options;
  add_daemon_options(app, options);
  CLI11_PARSE(app, argc, argv);

  const std::optional<hd::DaemonConfig> config = load_daemon_config(options);
  if (!config) return 2;
  spdlog::set_level(spdlog::level::from_str(config->daemon.log_level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

  hd::BenchSettings settings;
  try {
    settings = hd::bench_settings_from(*config);
  } catch (const hd::ConfigError& e) {
    std::cerr << "hystbenchd: configuration error: " << e.what() << "\n";
    return 2;
  }
  if (options.check_only) {
    std::cout << settings.config_json.dump(2) << "\n";
    return 0;
  }
  const std::optional<std::string> token = live_view_token(*config);
  if (!token) return 2;
  return run_daemon(*config, std::move(settings), *token, block_stop_signals());
}

}  // namespace

int main(int argc, char** argv) {
  return hystbench::common::run_main("hystbenchd", run, argc, argv);
}
