// Abuse and faults against the real hystbenchd: 100 concurrent clients during a 10 kHz run,
// hostile clients (slow readers, half-closed sockets, oversized lines, invalid UTF-8), the
// socket's permissions, injected sensor faults, and kill -9 mid-run followed by a restart.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/daemon/loop/sample_record.hpp"
#include "support/daemon_process.hpp"
#include "support/stuck_sensor_log.hpp"
#include "support/temp_dir_test.hpp"

namespace hd = hystbench::daemon;
namespace cli = hystbench::cli;
namespace fs = std::filesystem;
using hystbench::testing::Daemon;
using hystbench::testing::RawClient;
using hystbench::testing::wait_finished;
using nlohmann::json;

namespace {

/// A loopback configuration at `rate_hz`, with extra TOML appended (e.g. a [driver.loopback]).
std::string write_config(const fs::path& dir, int rate_hz, const std::string& extra = "") {
  fs::create_directories(dir);
  const fs::path path = dir / "bench.toml";
  std::ofstream(path) << "[daemon]\nlog_level = \"warn\"\n"
                      << "[loop]\nrate_hz = " << rate_hz
                      << "\nrealtime = true\noverrun_budget = 1000000\n"
                      << "[limits]\nu_min = 0.0\nu_max = 150.0\ny_min = 0.0\ny_max = 44.0\n"
                      << "[driver]\ntype = \"loopback\"\n"
                      << extra;
  return path.string();
}

/// VmRSS of a process [kB].
long rss_kb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

/// Jiffies of all CPUs from /proc/stat: {total, steal} (steal: time the hypervisor ran
/// something else while this VM wanted the CPU).
std::pair<double, double> cpu_jiffies() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  in >> cpu;
  double total = 0, steal = 0, v = 0;
  for (int i = 0; i < 8 && in >> v; ++i) {
    total += v;
    if (i == 7) steal = v;
  }
  return {total, steal};
}

/// Share of CPU time stolen by the hypervisor since `from` (cpu_jiffies()), 0..1.
double steal_share_since(const std::pair<double, double>& from) {
  const auto now = cpu_jiffies();
  const double total = now.first - from.first;
  return total > 0 ? (now.second - from.second) / total : 0.0;
}

/// A run log cut off at any byte (kill -9): everything up to the last complete line.
cli::DataTable read_complete_records(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto last_newline = text.rfind('\n');
  text.resize(last_newline == std::string::npos ? 0 : last_newline + 1);
  return cli::DataTable::parse_csv(text, path);
}

class AbuseTest : public hystbench::test::TempDirTest {
 protected:
  AbuseTest() : TempDirTest("hbabuse") {}
  void TearDown() override {
    daemon_.reset();
    TempDirTest::TearDown();
  }
  void start(const std::string& config = {}) {
    daemon_ = std::make_unique<Daemon>(dir_, config);
    ASSERT_TRUE(daemon_->running()) << "hystbenchd did not start";
  }
  /// A status request answered on a fresh connection.
  bool responsive() {
    try {
      cli::BenchClient c(daemon_->socket());
      return c.request("status", json::object(), std::chrono::seconds(5))["ok"] == true;
    } catch (const cli::ClientError&) {
      return false;
    }
  }
  std::unique_ptr<Daemon> daemon_;
};

}  // namespace

// One 3 s track at 10 kHz with 100 clients x 20 requests (status, unknown command, malformed
// JSON, a run while one is active) sent during it. Every client must get every reply, the run
// must complete with nothing dropped. The loop's wake latency and overruns are compared with
// the same run without clients: HYSTBENCH_ABUSE_PAIRS (default 1) alternating idle/loaded
// pairs; with 5 or more pairs in which the hypervisor stole under 2 % of the CPU, the medians
// are asserted (p99 within 10 % + 5 us, overruns within 10 % + 10 of the idle run's); with
// fewer they are printed only (two idle runs on a shared 2-core VM already differ by more than
// 10 %, and stolen time stalls any loop).
TEST_F(AbuseTest, HundredConcurrentClientsDuringA10kHzRunAllGetReplies) {
  start(write_config(dir_, 10000));
  cli::BenchClient c(daemon_->socket());
  const json track = {{"compensator", "none"}, {"periods", 3}, {"frequency_hz", 1}};
  const char* pairs_env = std::getenv("HYSTBENCH_ABUSE_PAIRS");
  const int pairs = pairs_env ? std::max(1, std::atoi(pairs_env)) : 1;
  constexpr int kClients = 100, kRequests = 20;
  // A pair counts towards the comparison only when the hypervisor stole less than this share
  // of the CPU during both of its runs: stolen time stalls the loop whatever the daemon does.
  constexpr double kMaxSteal = 0.02;
  std::vector<double> idle_p99, loaded_p99, idle_overruns, loaded_overruns;
  int stolen_pairs = 0;
  for (int pair = 0; pair < pairs; ++pair) {
    auto jiffies = cpu_jiffies();
    json r = c.request("track", track);
    ASSERT_TRUE(r["ok"]) << r.dump();
    const json idle = wait_finished(c, r["result"]["run_id"].get<std::string>());
    ASSERT_EQ(idle["end"], "completed") << idle.dump();
    const double idle_steal = steal_share_since(jiffies);

    jiffies = cpu_jiffies();
    r = c.request("track", track);
    ASSERT_TRUE(r["ok"]) << r.dump();
    std::atomic<int> replies{0}, wrong{0};
    std::vector<std::thread> clients;
    for (int i = 0; i < kClients; ++i) {
      clients.emplace_back([&, i] {
        RawClient raw(daemon_->socket());
        for (int k = 0; k < kRequests; ++k) {
          const int kind = (i + k) % 4;
          const std::string line =
              kind == 0   ? "{\"id\":" + std::to_string(k) + ",\"cmd\":\"status\"}\n"
              : kind == 1 ? "{\"id\":" + std::to_string(k) + ",\"cmd\":\"no.such\"}\n"
              : kind == 2 ? "{not json at all\n"
                          : "{\"id\":" + std::to_string(k) + ",\"cmd\":\"track\"}\n";  // busy
          raw.send(line);
          const json reply = raw.line();
          if (reply.is_null()) return;
          ++replies;
          if ((kind == 0) != reply.value("ok", false)) ++wrong;
        }
      });
    }
    for (auto& t : clients) t.join();
    const json loaded = wait_finished(c, r["result"]["run_id"].get<std::string>());
    const double loaded_steal = steal_share_since(jiffies);
    EXPECT_EQ(replies.load(), kClients * kRequests);
    EXPECT_EQ(wrong.load(), 0);
    ASSERT_EQ(loaded["end"], "completed") << loaded.dump();
    EXPECT_EQ(loaded["dropped"], 0);
    EXPECT_EQ(idle["dropped"], 0);
    const auto& li = idle["loop"]["wake_latency_ns"];
    const auto& ll = loaded["loop"]["wake_latency_ns"];
    std::cout << "pair " << pair + 1 << " of " << pairs << ", 10 kHz run, idle:   wake p50 "
              << li["p50"] << " ns, p99 " << li["p99"] << " ns, max " << li["max"]
              << " ns, overruns " << idle["overruns"] << " of " << idle["samples"] << ", steal "
              << 100.0 * idle_steal << " %\n"
              << "pair " << pair + 1 << " of " << pairs << ", 10 kHz run, loaded: wake p50 "
              << ll["p50"] << " ns, p99 " << ll["p99"] << " ns, max " << ll["max"]
              << " ns, overruns " << loaded["overruns"] << " of " << loaded["samples"] << " ("
              << kClients << " clients x " << kRequests << " requests), steal "
              << 100.0 * loaded_steal << " %\n";
    if (idle_steal > kMaxSteal || loaded_steal > kMaxSteal) {
      ++stolen_pairs;
      continue;
    }
    idle_p99.push_back(li["p99"].get<double>());
    loaded_p99.push_back(ll["p99"].get<double>());
    idle_overruns.push_back(idle["overruns"].get<double>());
    loaded_overruns.push_back(loaded["overruns"].get<double>());
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const int counted = static_cast<int>(idle_p99.size());
  if (counted == 0) {
    std::cout << "no pair without hypervisor steal above " << 100.0 * kMaxSteal
              << " %: latency comparison not made\n";
    return;
  }
  const double ip = median(idle_p99), lp = median(loaded_p99);
  const double io = median(idle_overruns), lo = median(loaded_overruns);
  std::cout << "median over " << counted << " pairs (" << stolen_pairs
            << " left out for steal): wake p99 idle " << ip << " ns, loaded " << lp << " ns ("
            << (ip > 0 ? 100.0 * (lp / ip - 1.0) : 0.0) << " %); overruns idle " << io
            << ", loaded " << lo << "\n";
  if (counted >= 5) {
    EXPECT_LE(lp, 1.1 * ip + 5000.0);
    EXPECT_LE(lo, 1.1 * io + 10.0);
  } else if (pairs >= 5) {
    std::cout << "only " << counted << " of " << pairs
              << " pairs ran without steal: the 10 % criterion is not asserted\n";
  }
}

TEST_F(AbuseTest, HostileClientsLeaveTheDaemonResponsiveAndBounded) {
  start();
  ASSERT_TRUE(responsive());
  const long rss_before = rss_kb(daemon_->pid());
  {
    // Slow readers: request status replies without ever reading them.
    std::vector<std::unique_ptr<RawClient>> slow;
    for (int i = 0; i < 5; ++i) {
      slow.push_back(std::make_unique<RawClient>(daemon_->socket(), false));
      const std::string burst = [] {
        std::string s;
        for (int k = 0; k < 200; ++k) s += "{\"cmd\":\"status\"}\n";
        return s;
      }();
      for (int k = 0; k < 200; ++k) {  // 40 000 requests, non-blocking: stop when refused
        if (::send(slow.back()->fd(), burst.data(), burst.size(), MSG_NOSIGNAL | MSG_DONTWAIT) < 0)
          break;
      }
    }
    EXPECT_TRUE(responsive());
    // Half-closed: a request, then the write side shut; the reply still arrives.
    for (int i = 0; i < 10; ++i) {
      RawClient half(daemon_->socket());
      half.send("{\"id\":1,\"cmd\":\"status\"}\n");
      ::shutdown(half.fd(), SHUT_WR);
      const json reply = half.line();
      EXPECT_TRUE(reply.value("ok", false)) << reply.dump();
    }
    // Half-closed mid-line, never completed.
    for (int i = 0; i < 10; ++i) {
      RawClient half(daemon_->socket());
      half.send("{\"id\":1,\"cmd\":\"sta");
      ::shutdown(half.fd(), SHUT_WR);
    }
    // Oversized lines: 8 MiB without a newline, then a valid request on the same connection.
    for (int i = 0; i < 4; ++i) {
      RawClient big(daemon_->socket());
      const std::string chunk(1 << 20, 'x');
      for (int k = 0; k < 8; ++k) big.send(chunk);
      EXPECT_EQ(big.line()["error"]["code"], "line_too_long");
      big.send("\n{\"id\":2,\"cmd\":\"status\"}\n");
      const json reply = big.line();
      EXPECT_TRUE(reply.value("ok", false)) << reply.dump().substr(0, 200);
    }
    // A number beyond double (fuzzer finding: it used to terminate the daemon).
    {
      RawClient big_number(daemon_->socket());
      big_number.send("{\"id\":1e999,\"cmd\":\"status\"}\n");
      EXPECT_EQ(big_number.line()["error"]["code"], "bad_json");
    }
    // Invalid UTF-8 and random bytes: every line gets a protocol error, never a crash.
    std::mt19937 rng(7);
    RawClient junk(daemon_->socket());
    for (int i = 0; i < 500; ++i) {
      std::string line = "{\"id\":" + std::to_string(i) + ",\"cmd\":\"";
      for (int k = 0; k < 40; ++k) {
        char ch = static_cast<char>(0x80 + rng() % 0x80);
        line += ch;
      }
      line += "\"}\n";
      junk.send(line);
      const json reply = junk.line();
      ASSERT_FALSE(reply.is_null()) << "no reply to line " << i;
      EXPECT_FALSE(reply.value("ok", true));
    }
    EXPECT_TRUE(responsive());
  }
  // Everything closed: memory back within a bound (a few MiB of buffers may stay allocated).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_TRUE(responsive());
  const long rss_after = rss_kb(daemon_->pid());
  std::cout << "VmRSS before " << rss_before << " kB, after " << rss_after << " kB\n";
  EXPECT_LT(rss_after, rss_before + 32 * 1024);
  cli::BenchClient c(daemon_->socket());
  EXPECT_EQ(c.request("status")["result"]["state"], "idle");
}

TEST_F(AbuseTest, SocketIsOnlyForTheOwnerAndGroup) {
  start();
  struct stat st {};
  ASSERT_EQ(::lstat(daemon_->socket().c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  EXPECT_EQ(st.st_mode & 07777, 0660u) << std::oct << (st.st_mode & 07777);
  EXPECT_EQ(st.st_uid, ::getuid());
  EXPECT_EQ(st.st_gid, ::getgid());
}

namespace {

struct FaultCase {
  const char* key;
  const char* reason;
};

}  // namespace

TEST_F(AbuseTest, SensorFaultsGoSafeWithinTheTickAndEndTheRunWithTheReason) {
  // 1 kHz; the fault is armed at an absolute driver tick (4 s after start-up), mid-run.
  // A stuck sensor is found loop.stuck_sensor_ms (20 ms: 20 ticks) after the output has moved
  // 2 % of its range (3 V) from where the reading froze (the loopback answers in the same tick).
  for (const FaultCase fc :
       {FaultCase{"read_error_at_tick", "driver read failed"},
        FaultCase{"nan_at_tick", "measurement is not a finite number"},
        FaultCase{
            "stuck_at_tick",
            "sensor stuck: the same reading while the output moved (loop.stuck_sensor_ms)"}}) {
    SCOPED_TRACE(fc.key);
    daemon_.reset();
    fs::remove_all(dir_);
    start(write_config(dir_, 1000,
                       std::string("[driver.loopback]\nfaults = { ") + fc.key + " = 4000 }\n"));
    cli::BenchClient c(daemon_->socket());
    const json r =
        c.request("track", {{"compensator", "none"}, {"periods", 20}, {"frequency_hz", 1}});
    ASSERT_TRUE(r["ok"]) << r.dump();
    const json result = wait_finished(c, r["result"]["run_id"].get<std::string>());
    ASSERT_EQ(result["end"], "fault") << result.dump();
    EXPECT_EQ(result["reason"], fc.reason);
    EXPECT_LT(result["samples"].get<std::uint64_t>(),
              result["planned_samples"].get<std::uint64_t>());
    EXPECT_EQ(result["output_v_after"], 0.0);  // the loopback's safe output
    EXPECT_EQ(result["dropped"], 0);
    // The log is intact and ends with the faulted tick.
    const auto log = cli::DataTable::read_csv(result["log"].get<std::string>());
    ASSERT_EQ(log.rows(), result["samples"].get<std::size_t>());
    const auto& index = log.column("index");
    const auto& flags = log.column("flags");
    for (std::size_t k = 0; k < index.size(); ++k) ASSERT_EQ(index[k], static_cast<double>(k));
    for (std::size_t k = 0; k + 1 < flags.size(); ++k)
      ASSERT_EQ(static_cast<unsigned>(flags[k]) & hd::kSampleFault, 0u) << "row " << k;
    EXPECT_NE(static_cast<unsigned>(flags.back()) & hd::kSampleFault, 0u);
    if (std::string(fc.key) == "stuck_at_tick") {
      // The reading froze; the output moved 3 V away from where it was then; the run ended
      // the window after that, not before and not later.
      const auto f = hystbench::test::find_frozen_reading(log, 3.0);
      ASSERT_TRUE(f.output_moved());
      // (+-1: the log's u is rounded to its printed digits.)
      EXPECT_NEAR(static_cast<double>(f.fault_after_moved()), 20.0, 1.0);
    }
    // The bench stays in FAULT, at the safe output, until reset.
    const json status = c.request("status")["result"];
    EXPECT_EQ(status["state"], "fault");
    EXPECT_EQ(status["output_v"], 0.0);
    EXPECT_FALSE(c.request("track", {{"compensator", "none"}})["ok"]);
  }
}

TEST_F(AbuseTest, KillNineMidRunLeavesAReadableLogAndTheNextStartRecovers) {
  const std::string config = write_config(dir_, 10000);
  start(config);
  std::string log_path;
  {
    cli::BenchClient c(daemon_->socket());
    const json r = c.request("track", {{"compensator", "none"}, {"periods", 100}});
    ASSERT_TRUE(r["ok"]) << r.dump();
    log_path = r["result"]["log"];
    std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  }
  EXPECT_EQ(daemon_->terminate(SIGKILL), 128 + SIGKILL);
  // Readable up to the last complete record, indices without gaps.
  const auto log = read_complete_records(log_path);
  EXPECT_GT(log.rows(), 0u);
  const auto& index = log.column("index");
  for (std::size_t k = 0; k < index.size(); ++k) ASSERT_EQ(index[k], static_cast<double>(k));
  std::cout << "kill -9 after 2 s at 10 kHz: " << log.rows() << " complete records\n";
  EXPECT_TRUE(fs::exists(fs::symlink_status(daemon_->socket())));  // the stale socket is left
  // The next start is not blocked by the stale socket, and a run completes.
  daemon_.reset();
  start(config);
  cli::BenchClient c(daemon_->socket());
  EXPECT_EQ(c.request("status")["result"]["state"], "idle");
  const json r = c.request("track", {{"compensator", "none"}, {"periods", 1}, {"frequency_hz", 2}});
  ASSERT_TRUE(r["ok"]) << r.dump();
  const json result = wait_finished(c, r["result"]["run_id"].get<std::string>());
  ASSERT_EQ(result["end"], "completed") << result.dump();
  // `latest` is a valid link to the new run's complete log.
  const fs::path latest = dir_ / "logs" / "latest.csv";
  ASSERT_TRUE(fs::is_symlink(latest));
  EXPECT_EQ(fs::canonical(latest), fs::canonical(result["log"].get<std::string>()));
  EXPECT_EQ(cli::DataTable::read_csv(latest.string()).rows(), result["samples"].get<std::size_t>());
}
