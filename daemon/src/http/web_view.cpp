#include "hystbench/daemon/http/web_view.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>
#include <utility>

#include "http/details/run_samples.hpp"
#include "http/details/web_assets.hpp"
#include "hystbench/common/command_error.hpp"
#include "hystbench/daemon/http/access_token.hpp"
#include "hystbench/daemon/http/scope_feed.hpp"
#include "hystbench/daemon/loop/loop_statistics.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "service/details/command_table.hpp"

// After Eigen (through bench.hpp): httplib.h brings <resolv.h>, whose _res macro breaks Eigen's
// declarations that follow it.
#include <httplib.h>

namespace hystbench::daemon {

using nlohmann::json;

namespace {

// The connection number the bench sees for every request of the view (a socket client's
// numbers count up from 1).
constexpr std::uint64_t kWebViewClient = std::numeric_limits<std::uint64_t>::max();
constexpr std::size_t kKeptEvents = 64;

constexpr const char* kPaths =
    "/, /api/view, /api/status, /api/runs, /api/runs/RUN_ID, /api/runs/RUN_ID/samples, "
    "/api/model, /api/timing, /api/stream, POST /api/command";

// The page may load its own files only; nothing from elsewhere, no framing.
const httplib::Headers kSecurityHeaders = {
    {"Content-Security-Policy",
     "default-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data:; "
     "frame-ancestors 'none'"},
    {"X-Content-Type-Options", "nosniff"},
    {"Referrer-Policy", "no-referrer"},
    {"Cache-Control", "no-store"}};

void reply_json(httplib::Response& res, const json& body, int status = 200) {
  res.status = status;
  res.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace), "application/json");
}

void refuse(httplib::Response& res, int status, const std::string& code,
            const std::string& message) {
  reply_json(res, {{"error", {{"code", code}, {"message", message}}}}, status);
}

// The reason phrase of the statuses the view refuses with, for a refusal httplib made itself.
std::pair<std::string, std::string> library_refusal(int status, const std::string& path) {
  switch (status) {
    case 404:
      return {"unknown_path", "no such path: " + path + " (there are " + kPaths + ")"};
    case 405:
      return {"bad_method", "this path does not take that method (" + std::string(kPaths) + ")"};
    case 413:
      return {"too_large", "the request is too large"};
    case 414:
      return {"too_large", "the request's path is too long"};
    default:
      return {"bad_request", "the request cannot be read (HTTP " + std::to_string(status) + ")"};
  }
}

int status_of(const common::CommandError& e) {
  const std::string& code = e.code();
  if (code == "unknown_run" || code == "unknown_command" || code == "no_model") return 404;
  if (code == "busy" || code == "no_run" || code == "fault") return 409;
  return 400;
}

json histogram_json(const LatencyHistogram& h) {
  json bins = json::array();
  const auto& counts = h.buckets();
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] == 0) continue;
    const std::int64_t from = LatencyHistogram::bucket_lower(i);
    const std::int64_t width = LatencyHistogram::bucket_width(i);
    bins.push_back({from, width > 0 ? from + width : h.max() + 1, counts[i]});
  }
  return {{"summary", to_json(h.summary())}, {"bins", std::move(bins)}};
}

WebViewOptions checked(WebViewOptions o) {
  if (o.port < 0 || o.port > 65535) throw WebViewError("http: the port must be in [0, 65535]");
  if (o.max_clients < 2 || o.max_clients > 64) {
    throw WebViewError("http: max_clients must be in [2, 64]");
  }
  if (o.control && o.token.size() < kMinAccessTokenLength) {
    throw WebViewError("http: control needs a token of at least " +
                       std::to_string(kMinAccessTokenLength) + " characters");
  }
  if (!(o.frame_rate_hz >= 1.0 && o.frame_rate_hz <= 100.0)) {
    throw WebViewError("http: frame_rate_hz must be in [1, 100]");
  }
  return o;
}

}  // namespace

WebView::WebView(WebViewOptions options, Bench& bench, ScopeFeed* feed)
    : options_(checked(std::move(options))), bench_(bench), feed_(feed) {}

WebView::~WebView() { stop(); }

void WebView::start() {
  if (server_) return;
  server_ = std::make_unique<httplib::Server>();
  httplib::Server& s = *server_;
  const std::size_t threads = options_.max_clients;
  s.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  s.set_payload_max_length(options_.max_body_bytes);
  s.set_read_timeout(options_.io_timeout);
  s.set_write_timeout(options_.io_timeout);
  s.set_keep_alive_timeout(2);
  s.set_default_headers(kSecurityHeaders);
  // Accepted connections inherit the listening socket's buffer size.
  s.set_socket_options([bytes = options_.send_buffer_bytes](socket_t sock) {
    const int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    setsockopt(sock, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
  });
  s.set_logger([this](const httplib::Request& req, const httplib::Response& res) {
    counters_.requests.fetch_add(1, std::memory_order_relaxed);
    if (res.status >= 400) {
      counters_.refused.fetch_add(1, std::memory_order_relaxed);
      spdlog::info("http {} {} {} refused ({})", req.remote_addr, req.method, req.path, res.status);
    }
  });
  s.set_error_handler(
      httplib::Server::HandlerWithResponse([](const httplib::Request& req, httplib::Response& res) {
        if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;  // ours
        const auto [code, message] = library_refusal(res.status, req.path);
        refuse(res, res.status, code, message);
        return httplib::Server::HandlerResponse::Handled;
      }));
  s.set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        // A route's refusal is the bench's CommandError, answered as the socket names it.
        try {
          std::rethrow_exception(std::move(ep));
        } catch (const common::CommandError& e) {
          refuse(res, status_of(e), e.code(), e.what());
        } catch (const std::exception& e) {
          refuse(res, 500, "internal", e.what());
        } catch (...) {
          refuse(res, 500, "internal", "unknown failure");
        }
      });
  add_routes();
  bound_port_ = options_.port == 0
                    ? s.bind_to_any_port(options_.host)
                    : (s.bind_to_port(options_.host, options_.port) ? options_.port : -1);
  if (bound_port_ < 0) {
    server_.reset();
    throw WebViewError("http: cannot listen on " + options_.host + ":" +
                       std::to_string(options_.port) +
                       " (in use, or not an address of this machine)");
  }
  stopping_.store(false, std::memory_order_release);
  thread_ = std::thread([this] { server_->listen_after_bind(); });
}

void WebView::stop() {
  if (!server_) return;
  stopping_.store(true, std::memory_order_release);
  server_->stop();
  if (thread_.joinable()) thread_.join();
  server_.reset();
}

std::string WebView::address() const {
  const bool v6 = options_.host.find(':') != std::string::npos;
  return (v6 ? "[" + options_.host + "]" : options_.host) + ":" + std::to_string(bound_port_);
}

WebViewCounters WebView::counters() const noexcept {
  return {counters_.requests.load(), counters_.refused.load(), counters_.streams.load(),
          counters_.streams_opened.load(), counters_.streams_dropped.load()};
}

void WebView::publish(const json& event) {
  std::string text =
      "event: bench\ndata: " + event.dump(-1, ' ', false, json::error_handler_t::replace) + "\n\n";
  std::lock_guard lock(events_mutex_);
  events_.push_back(std::move(text));
  ++events_next_;
  if (events_.size() > kKeptEvents) events_.pop_front();
}

void WebView::add_routes() {
  httplib::Server& s = *server_;
  for (const details::WebAsset& asset : details::web_assets()) {
    s.Get(std::string(asset.path), [&asset](const httplib::Request&, httplib::Response& res) {
      res.set_content(asset.content.data(), asset.content.size(),
                      std::string(asset.content_type).c_str());
    });
  }
  s.Get("/index.html",
        [](const httplib::Request&, httplib::Response& res) { res.set_redirect("/"); });
  // Reads through the bench's command table, as the socket's clients do.
  auto read_command = [this](const char* cmd) {
    return [this, cmd](const httplib::Request&, httplib::Response& res) {
      reply_json(res, bench_.handle(cmd, json::object(), kWebViewClient));
    };
  };
  s.Get("/api/status", read_command("status"));
  s.Get("/api/runs", read_command("runs"));
  s.Get("/api/model", [this](const httplib::Request&, httplib::Response& res) {
    try {
      reply_json(res, bench_.handle("model.get", json::object(), kWebViewClient));
    } catch (const common::CommandError& e) {
      if (e.code() != "no_model") throw;
      reply_json(res, nullptr);  // no model yet: the page says so
    }
  });
  s.Get("/api/view", [this](const httplib::Request&, httplib::Response& res) {
    reply_json(res, {{"version", HYSTBENCH_VERSION},
                     {"control", options_.control},
                     {"driver", options_.driver},
                     {"axes", options_.axes},
                     {"rate_hz", options_.rate_hz},
                     {"scope_rate_hz", options_.scope_rate_hz}});
  });
  s.Get(R"(/api/runs/([A-Za-z0-9._-]{1,128}))", [this](const httplib::Request& req,
                                                       httplib::Response& res) {
    reply_json(res, bench_.handle("run.get", {{"run_id", req.matches[1].str()}}, kWebViewClient));
  });
  s.Get(R"(/api/runs/([A-Za-z0-9._-]{1,128})/samples)", [this](const httplib::Request& req,
                                                               httplib::Response& res) {
    std::size_t points = 2000;
    if (req.has_param("points")) {
      const std::string text = req.get_param_value("points");
      char* end = nullptr;
      const long v = std::strtol(text.c_str(), &end, 10);
      if (end == text.c_str() || *end != '\0' || v < 10 || v > 20000) {
        refuse(res, 400, "bad_params", "points: an integer in [10, 20000]");
        return;
      }
      points = static_cast<std::size_t>(v);
    }
    reply_json(res, details::decimated_run_log(options_.log_dir, req.matches[1].str(), points));
  });
  s.Get("/api/timing", [this](const httplib::Request&, httplib::Response& res) {
    const LoopStatisticsSnapshot t = bench_.loop().statistics();
    reply_json(res, {{"ticks", t.ticks},
                     {"overruns", t.overruns},
                     {"skipped", t.skipped},
                     {"exec_ns", histogram_json(t.execution)},
                     {"wake_latency_ns", histogram_json(t.wake_latency)}});
  });
  s.Get("/api/stream",
        [this](const httplib::Request& req, httplib::Response& res) { stream(req, res); });
  s.Post("/api/command",
         [this](const httplib::Request& req, httplib::Response& res) { command(req, res); });
}

void WebView::command(const httplib::Request& req, httplib::Response& res) {
  json body = json::parse(req.body, nullptr, false);
  if (body.is_discarded() || !body.is_object()) {
    refuse(res, 400, "bad_json",
           "the body must be a JSON object {\"cmd\": ..., \"params\": {...}}");
    return;
  }
  if (!body.contains("cmd") || !body["cmd"].is_string()) {
    refuse(res, 400, "bad_request", "cmd: missing or not a string");
    return;
  }
  const std::string cmd = body["cmd"];
  const json params = body.value("params", json::object());
  if (!params.is_object()) {
    refuse(res, 400, "bad_request", "params: not an object");
    return;
  }
  // Commands that only read are answered without control and without the token.
  const bool read_only = details::command_reads_only(cmd);
  if (!read_only) {
    if (!options_.control) {
      refuse(res, 403, "control_off",
             "'" + cmd + "' changes the bench: the view is read-only (http.control = false)");
      return;
    }
    const std::string auth = req.get_header_value("Authorization");
    constexpr std::string_view kBearer = "Bearer ";
    if (auth.empty()) {
      refuse(res, 401, "no_token", "'" + cmd + "' needs the token (Authorization: Bearer ...)");
      return;
    }
    if (auth.compare(0, kBearer.size(), kBearer) != 0 ||
        !access_token_matches(options_.token, std::string_view(auth).substr(kBearer.size()))) {
      refuse(res, 401, "bad_token", "the token does not match the service's");
      return;
    }
    if (cmd.rfind("upload.", 0) == 0) {
      refuse(res, 400, "not_over_http",
             "uploads go through the command socket (hystbench, or the Python client)");
      return;
    }
  }
  try {
    reply_json(res, {{"ok", true}, {"result", bench_.handle(cmd, params, kWebViewClient)}});
  } catch (const common::CommandError& e) {
    json error = {{"code", e.code()}, {"message", e.what()}};
    if (e.detail().is_object()) error.update(e.detail());
    reply_json(res, {{"ok", false}, {"error", error}}, status_of(e));
  }
}

void WebView::stream(const httplib::Request&, httplib::Response& res) {
  if (counters_.streams.fetch_add(1) + 1 >= options_.max_clients) {
    counters_.streams.fetch_sub(1);
    refuse(res, 503, "too_many_streams",
           "every stream slot is taken (http.max_clients - 1 streams at once)");
    return;
  }
  counters_.streams_opened.fetch_add(1, std::memory_order_relaxed);
  std::uint64_t event_cursor = 0;
  {
    std::lock_guard lock(events_mutex_);
    event_cursor = events_next_;
  }
  std::uint64_t scope_cursor = feed_ != nullptr ? feed_->start_cursor() : 0;
  res.set_header("X-Accel-Buffering", "no");
  res.set_chunked_content_provider(
      "text/event-stream",
      [this, event_cursor, scope_cursor](std::size_t, httplib::DataSink& sink) mutable {
        if (stopping_.load(std::memory_order_acquire)) {
          sink.done();
          return true;
        }
        const std::string piece = next_piece(event_cursor, scope_cursor);
        if (!sink.write(piece.data(), piece.size())) {
          counters_.streams_dropped.fetch_add(1, std::memory_order_relaxed);
          return false;
        }
        return true;
      },
      [this](bool) { counters_.streams.fetch_sub(1); });
}

std::string WebView::next_piece(std::uint64_t& event_cursor, std::uint64_t& scope_cursor) {
  const auto period = std::chrono::milliseconds(
      static_cast<std::int64_t>(std::lround(1000.0 / options_.frame_rate_hz)));
  const auto until = std::chrono::steady_clock::now() + period;
  std::string piece;
  {
    std::lock_guard lock(events_mutex_);
    const std::uint64_t oldest = events_next_ - events_.size();
    event_cursor = std::max(event_cursor, oldest);
    for (; event_cursor < events_next_; ++event_cursor) piece += events_[event_cursor - oldest];
  }
  if (feed_ != nullptr) {
    // At most one frame a period: a scope that redraws with each piece runs at frame_rate_hz.
    std::this_thread::sleep_until(until);
    const std::string frame = feed_->frame_after(scope_cursor, std::chrono::milliseconds(1000));
    if (!frame.empty()) piece += "event: scope\ndata: " + frame + "\n\n";
  } else if (piece.empty()) {
    std::this_thread::sleep_until(until + std::chrono::milliseconds(960));
  }
  if (piece.empty()) piece = ": keep-alive\n\n";
  return piece;
}

}  // namespace hystbench::daemon
