// The real daemon, driven through its socket: a run from start to end, every bad input,
// a client killed mid-run, SIGTERM mid-run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "hystbench/daemon/bench_client.hpp"
#include "hystbench/daemon/data_table.hpp"

extern char** environ;

namespace hd = hystbench::daemon;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

class Daemon {
 public:
  explicit Daemon(const fs::path& dir) : dir_(dir) {
    fs::create_directories(dir_);
    socket_ = (dir_ / "s.sock").string();
    const std::string bin = std::string(HYSTBENCH_BIN_DIR) + "/hystbenchd";
    const std::string config = std::string(HYSTBENCH_SOURCE_DIR) + "/config/loopback.toml";
    const std::string logs = (dir_ / "logs").string(), models = (dir_ / "models").string();
    const std::string out = (dir_ / "daemon.log").string();
    std::vector<std::string> args{bin,         "--config", config,        "--socket", socket_,
                                  "--log-dir", logs,       "--model-dir", models};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    if (posix_spawn(&pid_, bin.c_str(), &fa, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
    for (int i = 0; i < 200 && pid_ > 0; ++i) {
      if (fs::exists(socket_)) {
        try {
          hd::BenchClient probe(socket_);
          return;
        } catch (const hd::ClientError&) {
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
  }
  ~Daemon() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  /// Sends a signal and returns the exit status (or -1 on timeout).
  int terminate(int sig = SIGTERM) {
    ::kill(pid_, sig);
    for (int i = 0; i < 400; ++i) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    return -1;
  }
  const std::string& socket() const { return socket_; }
  bool running() const { return pid_ > 0 && ::kill(pid_, 0) == 0; }

 private:
  fs::path dir_;
  std::string socket_;
  pid_t pid_ = -1;
};

// A raw connection for sending arbitrary bytes.
class RawClient {
 public:
  explicit RawClient(const std::string& path) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    line();  // greeting
  }
  ~RawClient() { ::close(fd_); }
  void send(const std::string& bytes) {
    std::size_t off = 0;
    while (off < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return;
      off += static_cast<std::size_t>(n);
    }
  }
  // Next line that is not an event.
  json line() {
    for (;;) {
      const auto nl = buf_.find('\n');
      if (nl != std::string::npos) {
        json j = json::parse(buf_.substr(0, nl));
        buf_.erase(0, nl + 1);
        if (j.contains("event")) continue;
        return j;
      }
      char c[4096];
      const ssize_t n = ::recv(fd_, c, sizeof c, 0);
      if (n <= 0) return json();
      buf_.append(c, static_cast<std::size_t>(n));
    }
  }

 private:
  int fd_ = -1;
  std::string buf_;
};

class HystbenchdTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("hbd_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    daemon_ = std::make_unique<Daemon>(dir_);
    ASSERT_TRUE(daemon_->running()) << "hystbenchd did not start";
  }
  void TearDown() override {
    daemon_.reset();
    fs::remove_all(dir_);
  }
  json wait_finished(hd::BenchClient& c, const std::string& run_id, int seconds = 120) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    while (std::chrono::steady_clock::now() < until) {
      auto e = c.next_event(std::chrono::milliseconds(500));
      if (e && (*e)["event"] == "run.finished" && (*e)["result"]["run_id"] == run_id) {
        return (*e)["result"];
      }
    }
    return json();
  }
  fs::path dir_;
  std::unique_ptr<Daemon> daemon_;
};

}  // namespace

TEST_F(HystbenchdTest, TrackRunFromStartToEndOverTheSocket) {
  hd::BenchClient c(daemon_->socket());
  EXPECT_EQ(c.greeting()["hello"], "hystbenchd");
  json r = c.request("track", {{"compensator", "none"}, {"periods", 2}, {"frequency_hz", 2}});
  ASSERT_TRUE(r["ok"]) << r.dump();
  EXPECT_EQ(r["id"], 1);
  const std::string run_id = r["result"]["run_id"];
  const json result = wait_finished(c, run_id);
  ASSERT_EQ(result["end"], "completed") << result.dump();
  EXPECT_EQ(result["dropped"], 0);
  const auto log = hd::DataTable::read_csv(result["log"].get<std::string>());
  EXPECT_EQ(log.rows(), result["samples"].get<std::size_t>());
  const json status = c.request("status")["result"];
  EXPECT_EQ(status["state"], "idle");
  EXPECT_EQ(status["last_result"]["run_id"], run_id);
}

TEST_F(HystbenchdTest, BadInputGetsAClearErrorAndChangesNothing) {
  RawClient raw(daemon_->socket());
  auto code_of = [&](const std::string& line) {
    raw.send(line);
    const json j = raw.line();
    EXPECT_FALSE(j.value("ok", true)) << line.substr(0, 200);
    return j["error"]["code"].get<std::string>();
  };
  EXPECT_EQ(code_of("{not json\n"), "bad_json");
  EXPECT_EQ(code_of("{\"id\":1,\"cmd\":\"fly\"}\n"), "unknown_command");
  EXPECT_EQ(code_of("{\"id\":2,\"cmd\":42}\n"), "bad_request");
  EXPECT_EQ(code_of("{\"id\":3,\"cmd\":\"track\",\"params\":{\"frequency_hz\":\"fast\"}}\n"),
            "bad_params");
  EXPECT_EQ(code_of("{\"id\":4,\"cmd\":\"track\",\"params\":{\"min_um\":-500,\"max_um\":10}}\n"),
            "out_of_range");
  EXPECT_EQ(code_of("{\"id\":5,\"cmd\":\"track\",\"params\":{\"compensator\":\"inverse\"}}\n"),
            "no_model");
  EXPECT_EQ(code_of(std::string(70 * 1024, 'x') + "\n"), "line_too_long");
  EXPECT_EQ(code_of("\xff\xfe{\"cmd\":\"status\"}\n"), "bad_json");
  // The connection still works and nothing changed.
  raw.send("{\"id\":9,\"cmd\":\"status\"}\n");
  const json s = raw.line();
  EXPECT_TRUE(s["ok"]);
  EXPECT_EQ(s["result"]["state"], "idle");
  EXPECT_TRUE(s["result"]["last_result"].is_null());
  // A run while one is active.
  hd::BenchClient c(daemon_->socket());
  ASSERT_TRUE(c.request("track", {{"compensator", "none"}, {"periods", 50}})["ok"]);
  const json busy = c.request("identify");
  EXPECT_FALSE(busy["ok"]);
  EXPECT_EQ(busy["error"]["code"], "busy");
  EXPECT_TRUE(c.request("stop")["ok"]);
}

TEST_F(HystbenchdTest, ClientKilledMidRunDoesNotDisturbTheRun) {
  std::string run_id;
  {
    // The client that starts the run, in a child process killed mid-run.
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const pid_t child = ::fork();
    if (child == 0) {
      ::close(fds[0]);
      hd::BenchClient c(daemon_->socket());
      const json r = c.request("track", {{"compensator", "none"}, {"periods", 3}});
      const std::string id = r["result"]["run_id"].get<std::string>() + "\n";
      (void)!::write(fds[1], id.data(), id.size());
      for (;;) c.next_event(std::chrono::seconds(1));
    }
    ::close(fds[1]);
    char buf[256] = {};
    const ssize_t n = ::read(fds[0], buf, sizeof buf - 1);
    ::close(fds[0]);
    ASSERT_GT(n, 1);
    run_id.assign(buf, static_cast<std::size_t>(n - 1));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
  }
  hd::BenchClient c(daemon_->socket());
  json last;
  for (int i = 0; i < 200; ++i) {
    last = c.request("status")["result"]["last_result"];
    if (!last.is_null()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(last["run_id"], run_id);
  EXPECT_EQ(last["end"], "completed");
  EXPECT_EQ(last["dropped"], 0);
}

TEST_F(HystbenchdTest, SigtermMidRunGoesSafeClosesTheLogAndExitsZero) {
  hd::BenchClient c(daemon_->socket());
  json r = c.request("track", {{"compensator", "none"}, {"periods", 100}});
  ASSERT_TRUE(r["ok"]);
  const std::string log_path = r["result"]["log"];
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_EQ(daemon_->terminate(SIGTERM), 0);
  // The run ended as aborted with the output at the safe value, and the daemon said so.
  json finished;
  for (;;) {
    std::optional<json> e;
    try {
      e = c.next_event(std::chrono::milliseconds(200));
    } catch (const hd::ClientError&) {
      break;  // the daemon closed the socket
    }
    if (!e) break;
    if ((*e)["event"] == "run.finished") finished = (*e)["result"];
  }
  ASSERT_FALSE(finished.is_null());
  EXPECT_EQ(finished["end"], "aborted");
  EXPECT_EQ(finished["output_v_after"], 0.0);
  // The log is complete and readable: one row per sample, indices without gaps.
  const auto log = hd::DataTable::read_csv(log_path);
  EXPECT_EQ(log.rows(), finished["samples"].get<std::size_t>());
  const auto& index = log.column("index");
  for (std::size_t k = 0; k < index.size(); ++k) ASSERT_EQ(index[k], static_cast<double>(k));
  EXPECT_FALSE(fs::exists(daemon_->socket()));
}
