// The live view over HTTP (http/web_view.hpp) on an in-process bench: the page from memory, the
// bench's reads through the command table, a run in the list with its plot, the scope stream,
// and every refusal of bad input: no token, bad token, read-only, oversized, unknown path,
// a client that stops reading (dropped, the others served), one that vanishes.
#include "hystbench/daemon/http/web_view.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>

#include "hystbench/daemon/http/scope_feed.hpp"
#include "support/bench_fixture.hpp"

// After Eigen (through the bench): httplib.h's <resolv.h> defines _res.
#include <httplib.h>

namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

constexpr const char* kToken = "s3cret-token-for-the-test";

class WebViewTest : public hystbench::test::BenchFixture {
 protected:
  WebViewTest() : BenchFixture("web_view") {}

  void TearDown() override {
    if (view_) view_->stop();
    if (feed_) feed_->stop();
    BenchFixture::TearDown();
  }

  /// The loopback bench on the simulated clock (0-44 um; `toml`, the 10 kHz default), its scope
  /// tap at 500 samples/s as hystbenchd makes it, the feed and the view.
  void start_view(bool control, std::chrono::seconds io_timeout = std::chrono::seconds(5),
                  const std::string& toml = loopback_toml(), int send_buffer_bytes = 64 << 10) {
    hd::BenchSettings s = settings_from_toml(toml);
    tap_ =
        std::make_unique<hd::ScopeTap>(hd::ScopeTap::decimation_for(s.loop.rate_hz, 500.0), 4096);
    s.loop.scope = tap_.get();
    hd::ScopeFeedOptions feed;
    feed.loop_rate_hz = s.loop.rate_hz;
    start(std::move(s));
    feed_ = std::make_unique<hd::ScopeFeed>(*tap_, feed);
    feed_->start();
    hd::WebViewOptions o;
    o.control = control;
    o.token = control ? kToken : "";
    o.log_dir = dir_ / "logs";
    o.io_timeout = io_timeout;
    o.send_buffer_bytes = send_buffer_bytes;
    view_ = std::make_unique<hd::WebView>(o, *bench_, feed_.get());
    view_->start();
    port_ = std::stoi(view_->address().substr(view_->address().rfind(':') + 1));
  }

  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(10);
    return c;
  }

  /// POST /api/command; the status and the reply.
  std::pair<int, json> command(const json& body, const std::string& token = "") const {
    httplib::Client c = client();
    httplib::Headers headers;
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    auto r = c.Post("/api/command", headers, body.dump(), "application/json");
    if (!r) return {0, json()};
    return {r->status, json::parse(r->body, nullptr, false)};
  }

  json get_json(const std::string& path, int expected_status = 200) const {
    httplib::Client c = client();
    auto r = c.Get(path);
    if (!r) {
      ADD_FAILURE() << "GET " << path << ": no reply";
      return json();
    }
    EXPECT_EQ(r->status, expected_status) << path << ": " << r->body;
    return json::parse(r->body, nullptr, false);
  }

  std::unique_ptr<hd::ScopeTap> tap_;
  std::unique_ptr<hd::ScopeFeed> feed_;
  std::unique_ptr<hd::WebView> view_;
  int port_ = 0;
};

const json kShortTrack = {
    {"cmd", "track"},
    {"params",
     {{"reference", "sine"}, {"frequency_hz", 20.0}, {"periods", 4}, {"compensator", "none"}}}};

// A raw connection that asks for the stream: it may then stop reading, or go away.
int open_stream_socket(int port, int receive_buffer) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const std::string request = "GET /api/stream HTTP/1.1\r\nHost: x\r\n\r\n";
  EXPECT_EQ(::send(fd, request.data(), request.size(), 0), static_cast<ssize_t>(request.size()));
  return fd;
}

template <class Done>
bool eventually(Done done, std::chrono::seconds timeout = std::chrono::seconds(20)) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

}  // namespace

TEST_F(WebViewTest, ServesThePageAndItsPlottingLibraryFromTheDaemon) {
  start_view(false);
  httplib::Client c = client();
  auto page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->get_header_value("Content-Type").find("text/html"), std::string::npos);
  EXPECT_NE(page->body.find("vendor/uPlot.iife.min.js"), std::string::npos);
  // Nothing from elsewhere: the page names no other host, and the browser is told so.
  EXPECT_EQ(page->body.find("http://"), std::string::npos);
  EXPECT_EQ(page->body.find("https://"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'self'"),
            std::string::npos);
  auto uplot = c.Get("/vendor/uPlot.iife.min.js");
  ASSERT_TRUE(uplot);
  EXPECT_EQ(uplot->status, 200);
  EXPECT_GT(uplot->body.size(), 20000u);
  EXPECT_NE(uplot->body.find("uPlot"), std::string::npos);
  const json view = get_json("/api/view");
  EXPECT_EQ(view["control"], false);
  EXPECT_EQ(view["driver"], "loopback");
  EXPECT_EQ(view["axes"], json::array({""}));
  EXPECT_TRUE(get_json("/api/model").is_null());  // no model yet: the page says so
}

TEST_F(WebViewTest, RefusesBadRequestsWithTheirCauseAndKeepsServing) {
  start_view(false);
  const json unknown = get_json("/api/nothing-here", 404);
  EXPECT_EQ(unknown["error"]["code"], "unknown_path");
  EXPECT_NE(unknown["error"]["message"].get<std::string>().find("/api/status"), std::string::npos);
  httplib::Client c = client();
  auto big = c.Post("/api/command", std::string(200 * 1024, ' '), "application/json");
  ASSERT_TRUE(big);
  EXPECT_EQ(big->status, 413);
  EXPECT_EQ(json::parse(big->body)["error"]["code"], "too_large");
  auto [status, bad] = command(json("not an object"));
  EXPECT_EQ(status, 400);
  EXPECT_EQ(bad["error"]["code"], "bad_json");
  const json no_run = get_json("/api/runs/20260101T000000Z-track-9", 404);
  EXPECT_EQ(no_run["error"]["code"], "unknown_run");
  EXPECT_EQ(get_json("/api/runs/no-such-run/samples", 404)["error"]["code"], "unknown_run");
  EXPECT_EQ(get_json("/api/runs/x/samples?points=3", 400)["error"]["code"], "bad_params");
  // Still serving, and the counters saw the refusals (the server counts a request after its
  // answer is written, so a count may arrive after the client has read the answer).
  EXPECT_EQ(get_json("/api/status")["state"], "idle");
  EXPECT_TRUE(eventually([&] { return view_->counters().refused >= 6u; }))
      << view_->counters().refused;
}

TEST_F(WebViewTest, IsReadOnlyUnlessControlIsOn) {
  start_view(false);
  auto [status, reply] = command(kShortTrack, kToken);
  EXPECT_EQ(status, 403);
  EXPECT_EQ(reply["error"]["code"], "control_off");
  auto [read_status, read] = command({{"cmd", "status"}});
  EXPECT_EQ(read_status, 200);
  EXPECT_EQ(read["ok"], true);
  EXPECT_EQ(read["result"]["state"], "idle");
  EXPECT_EQ(get_json("/api/status")["run"], nullptr);  // nothing was started
}

TEST_F(WebViewTest, ARunStartedWithTheTokenAppearsInTheListWithItsPlot) {
  start_view(true);
  auto [no_token, r1] = command(kShortTrack);
  EXPECT_EQ(no_token, 401);
  EXPECT_EQ(r1["error"]["code"], "no_token");
  auto [wrong, r2] = command(kShortTrack, "s3cret-token-for-the-tesT");
  EXPECT_EQ(wrong, 401);
  EXPECT_EQ(r2["error"]["code"], "bad_token");
  auto [upload, r3] = command({{"cmd", "upload.cancel"}, {"params", {{"upload", "u"}}}}, kToken);
  EXPECT_EQ(upload, 400);
  EXPECT_EQ(r3["error"]["code"], "not_over_http");

  auto [started, reply] = command(kShortTrack, kToken);
  ASSERT_EQ(started, 200) << reply.dump();
  EXPECT_EQ(reply["ok"], true);
  ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(60)));
  const std::string run_id = reply["result"]["run_id"];
  const json runs = get_json("/api/runs")["runs"];
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0]["run_id"], run_id);
  EXPECT_EQ(runs[0]["kind"], "track");
  EXPECT_EQ(runs[0]["end"], "completed");
  EXPECT_TRUE(runs[0]["rms_error_percent"].is_number());
  EXPECT_TRUE(runs[0]["finished"].is_string());
  EXPECT_EQ(get_json("/api/runs/" + run_id)["run_id"], run_id);
  const json plot = get_json("/api/runs/" + run_id + "/samples?points=100");
  const std::size_t rows = plot["rows"];
  ASSERT_GT(rows, 1000u);
  ASSERT_LE(plot["t"].size(), 100u);
  ASSERT_GE(plot["t"].size(), 50u);
  const json& axis = plot["axes"][0];
  double lo = INFINITY, hi = -INFINITY;
  for (const json& y : axis["y"]) {
    ASSERT_TRUE(y.is_number());
    lo = std::min(lo, y.get<double>());
    hi = std::max(hi, y.get<double>());
  }
  EXPECT_GT(hi - lo, 5.0);  // the sine moved the actuator
  EXPECT_EQ(axis["yr"].size(), plot["t"].size());
  // The precondition sweep follows no reference: none is drawn there (null), and the reference
  // after it is.
  ASSERT_TRUE(axis["yr"].front().is_null()) << axis["yr"].dump();
  ASSERT_TRUE(axis["yr"].back().is_number()) << axis["yr"].dump();
  // A second run after the first: both listed, newest first.
  auto [again, reply2] = command(kShortTrack, kToken);
  ASSERT_EQ(again, 200) << reply2.dump();
  ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(60)));
  const json both = get_json("/api/runs")["runs"];
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[0]["run_id"], reply2["result"]["run_id"]);
}

namespace {

// What a stream carried while a run played on the bench: its scope frames in order, the spacing
// of their samples, whether any was the run's, and the run's events.
struct StreamSeen {
  std::size_t frames = 0;
  double dt = 0.0;
  bool running = false;
  bool ordered = true;
  bool progress = false;
  bool finished = false;
};

StreamSeen parse_stream(const std::string& received) {
  StreamSeen seen;
  long last_seq = -1;
  for (std::size_t at = received.find("event: scope\ndata: "); at != std::string::npos;
       at = received.find("event: scope\ndata: ", at + 1)) {
    const std::size_t from = at + 19;
    const std::size_t end = received.find('\n', from);
    if (end == std::string::npos) break;  // its data line has not arrived whole yet
    const json f = json::parse(received.substr(from, end - from));
    seen.ordered = seen.ordered && f["seq"].get<long>() > last_seq;
    last_seq = f["seq"].get<long>() + static_cast<long>(f["y"][0].size()) - 1;
    seen.running = seen.running || f["running"].get<bool>();
    seen.dt = f["dt"].get<double>();
    ++seen.frames;
  }
  seen.progress = received.find("\"event\":\"run.progress\"") != std::string::npos;
  seen.finished = received.find("\"event\":\"run.finished\"") != std::string::npos;
  return seen;
}

// Reads the stream while a short track plays, until its end and 3 scope frames; what it carried.
// On the simulated clock the run plays in a burst and the idle stands still for a grace after
// it, so the frames may come after the run's end, once the idle is paced again.
StreamSeen stream_during_a_track(int port, const json& track) {
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(10);
  std::string received;
  std::thread reader([&] {
    c.Get("/api/stream", [&](const char* data, std::size_t n) {
      received.append(data, n);
      if (received.size() >= 400000) return false;
      const StreamSeen seen = parse_stream(received);
      return seen.frames < 3 || !seen.finished;
    });
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  httplib::Client post("127.0.0.1", port);
  auto r = post.Post("/api/command", {{"Authorization", std::string("Bearer ") + kToken}},
                     track.dump(), "application/json");
  EXPECT_TRUE(r && r->status == 200) << (r ? r->body : "no reply");
  reader.join();
  return parse_stream(received);
}

}  // namespace

TEST_F(WebViewTest, TheStreamCarriesScopeFramesAndTheBenchsEvents) {
  start_view(true);
  bench_->set_event_sink([this](const json& e) { view_->publish(e); });
  const StreamSeen seen = stream_during_a_track(port_, kShortTrack);
  EXPECT_GE(seen.frames, 3u);
  EXPECT_TRUE(seen.ordered);
  EXPECT_TRUE(seen.running);
  EXPECT_DOUBLE_EQ(seen.dt, 0.002);  // every 20th tick of 10 kHz
  EXPECT_TRUE(seen.progress);
  EXPECT_TRUE(seen.finished);
}

TEST_F(WebViewTest, OnASlowBenchTheScopeTakesEveryOtherTick) {
  start_view(true, std::chrono::seconds(5), slow_bench_toml());  // 1 kHz, a 190 Hz mode
  bench_->set_event_sink([this](const json& e) { view_->publish(e); });
  json track = kShortTrack;
  track["params"]["frequency_hz"] = 10.0;
  const StreamSeen seen = stream_during_a_track(port_, track);
  EXPECT_GE(seen.frames, 3u);
  EXPECT_TRUE(seen.ordered);
  EXPECT_TRUE(seen.running);
  EXPECT_DOUBLE_EQ(seen.dt, 0.002);  // 500 samples/s from 1 kHz
  EXPECT_TRUE(seen.finished);
}

TEST_F(WebViewTest, AClientThatStopsReadingIsDroppedAndTheOthersAreServed) {
  // A small send buffer fills in a fraction of a second of idle frames.
  start_view(false, std::chrono::seconds(1), loopback_toml(), 4096);
  const int stalled = open_stream_socket(port_, 4096);  // sends its request, never reads
  EXPECT_TRUE(eventually([&] { return view_->counters().streams_dropped >= 1; }))
      << "the stalled stream is still open";
  EXPECT_EQ(get_json("/api/status")["state"], "idle");
  ::close(stalled);

  const int vanished = open_stream_socket(port_, 1 << 16);
  EXPECT_TRUE(eventually([&] { return view_->counters().streams == 1; }));
  ::close(vanished);  // goes away mid-stream
  EXPECT_TRUE(eventually([&] { return view_->counters().streams == 0; }));
  EXPECT_EQ(get_json("/api/status")["state"], "idle");
}
