// The bench over CAN: hystbench-simamp as the amplifier on a socketpair carrying struct
// can_frame (this machine has no CAN kernel support), the Bench in-process. Fault tests: the
// amplifier goes silent, sends a malformed frame, reports bus-off: each run ends in FAULT with
// the output safe and every sample logged.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/config/daemon_settings.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "peer_process.hpp"

namespace hdm = hystbench::daemon;
namespace cli = hystbench::cli;
namespace ht = hystbench::test;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

class CanBenchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("hystbench_can_bench_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
  }
  void TearDown() override {
    bench_.reset();
    amp_.reset();
    if (fd_ >= 0) ::close(fd_);
    std::filesystem::remove_all(dir_);
  }
  /// hystbench-simamp with `amp_args` on the other end of a socketpair (fd_ is the bench's).
  void start_amplifier(std::vector<std::string> amp_args) {
    int sv[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv), 0);
    std::vector<std::string> argv{ht::bin("hystbench-simamp"), "--fd", "3"};
    argv.insert(argv.end(), amp_args.begin(), amp_args.end());
    amp_ = std::make_unique<ht::PeerProcess>(argv, sv[1]);
    ::close(sv[1]);
    fd_ = sv[0];
    ASSERT_TRUE(amp_->wait_for("ready on fd 3", 5s));
  }
  void start_bench(hdm::BenchSettings s) {
    s.log_dir = (dir_ / "logs").string();
    s.model_dir = (dir_ / "models").string();
    bench_ = std::make_unique<hdm::Bench>(s);
    bench_->set_event_sink([this](const json& e) {
      if (e["event"] == "run.finished") {
        std::lock_guard lock(m_);
        results_.push_back(e["result"]);
      }
    });
    bench_->start();
  }
  void start(std::vector<std::string> amp_args) {
    start_amplifier(std::move(amp_args));
    hdm::BenchSettings s;
    s.loop.rate_hz = 2000.0;
    s.loop.realtime.fifo = false;
    s.loop.realtime.lock_memory = false;
    s.loop.overrun_budget = 1000000;
    s.driver_type = "can";
    // Generous: a loaded CI machine may not schedule the simulator for tens of milliseconds.
    s.driver_params = {{"socket_fd", fd_}, {"heartbeat_timeout_ms", 200}};
    s.y_min = 0.0;
    s.y_max = 40.0;
    s.precondition_s = 0.2;
    start_bench(s);
  }
  json track(double periods) {
    bench_->handle("track", {{"compensator", "none"}, {"periods", periods}});
    EXPECT_TRUE(bench_->wait_idle(30s));
    std::lock_guard lock(m_);
    return results_.empty() ? json() : results_.back();
  }
  /// The run ended in FAULT, safe output, every sample logged; returns the driver's fault.
  std::string expect_safe_fault(const json& r) {
    EXPECT_EQ(r["end"], "fault") << r.dump(2);
    EXPECT_EQ(r["reason"], "driver read failed");
    EXPECT_DOUBLE_EQ(bench_->loop().last_output(), bench_->driver().safe_output_v());
    const json st = bench_->handle("status", json::object());
    EXPECT_EQ(st["state"], "fault");
    EXPECT_EQ(st["driver"]["output_v"].get<double>(), bench_->driver().safe_output_v());
    const auto table = cli::DataTable::read_csv(r["log"].get<std::string>());
    EXPECT_EQ(table.rows(), r["samples"].get<std::size_t>());
    EXPECT_EQ(r["logged"], r["samples"]);
    return st["driver"]["last_fault"].get<std::string>();
  }

  std::filesystem::path dir_;
  std::unique_ptr<ht::PeerProcess> amp_;
  int fd_ = -1;
  std::unique_ptr<hdm::Bench> bench_;
  std::mutex m_;
  std::vector<json> results_;
};

}  // namespace

TEST_F(CanBenchTest, TrackRunOverCanFrames) {
  start({});
  const json r = track(2);
  ASSERT_EQ(r["end"], "completed") << r.dump(2);
  EXPECT_EQ(r["dropped"], 0);
  EXPECT_GT(r["hysteresis_percent"].get<double>(), 8.0);  // no compensation: the plant's own
  const json st = bench_->handle("status", json::object());
  EXPECT_EQ(st["driver"]["malformed_frames"], 0);
  EXPECT_GT(st["driver"]["feedback_frames"].get<int>(), 1000);
}

// A stage over CAN, a node per axis, configured as a user writes it ([driver.can] axes):
// hystbench-simamp --stage xy answers each axis's node, the Lissajous moves each axis over its
// range, and the result is given per axis.
TEST_F(CanBenchTest, AStageOfANodePerAxisTracksEveryAxis) {
  start_amplifier({"--stage", "xy"});
  // Generous heartbeat as above: a loaded CI machine may not schedule the simulator in time.
  const std::string toml =
      "[loop]\nrate_hz = 2000\noverrun_budget = 1000000\n"
      "[limits]\ny_min = 0.0\ny_max = 44.0\n"
      "[driver]\ntype = \"can\"\n"
      "[driver.can]\nsocket_fd = " +
      std::to_string(fd_) + "\nheartbeat_timeout_ms = 200\naxes = [\"x\", \"y\"]\n";
  hdm::BenchSettings s = hdm::bench_settings_from(hdm::parse_config(toml));
  ASSERT_EQ(s.axes, (std::vector<std::string>{"x", "y"}));
  s.loop.realtime.fifo = false;
  s.loop.realtime.lock_memory = false;
  s.precondition_s = 0.2;
  start_bench(s);
  bench_->handle("track", {{"reference", "lissajous"}});
  ASSERT_TRUE(bench_->wait_idle(30s));
  json r;
  {
    std::lock_guard lock(m_);
    ASSERT_FALSE(results_.empty());
    r = results_.back();
  }
  ASSERT_EQ(r["end"], "completed") << r.dump(2);
  EXPECT_EQ(r["dropped"], 0);
  for (const char* axis : {"x", "y"}) {
    EXPECT_GT(r["axes"][axis]["range_um"].get<double>(), 20.0) << axis << r["axes"].dump();
  }
  // y's motion shows on x and x's on y: each node is its own axis of the coupled stage.
  EXPECT_GT(std::abs(r["coupling_error"]["y"]["gain_from"]["x"].get<double>()), 0.02)
      << r["coupling_error"].dump();
  const json st = bench_->handle("status", json::object());
  EXPECT_EQ(st["driver"]["malformed_frames"], 0);
  EXPECT_EQ(st["driver"]["axis_names"], json({"x", "y"}));
}

TEST_F(CanBenchTest, MissingFeedbackFaults) {
  start({"--stop-feedback-after", "2000"});
  const std::string why = expect_safe_fault(track(5));
  EXPECT_NE(why.find("no feedback frame 0x180 for"), std::string::npos) << why;
}

TEST_F(CanBenchTest, MalformedFrameFaults) {
  start({"--malformed-after", "2000"});
  const std::string why = expect_safe_fault(track(5));
  EXPECT_EQ(why, "malformed feedback frame 0x180: 4 data bytes, expected 5");
}

TEST_F(CanBenchTest, BusOffFaults) {
  start({"--bus-off-after", "2000"});
  const std::string why = expect_safe_fault(track(5));
  EXPECT_NE(why.find("bus-off"), std::string::npos) << why;
}
