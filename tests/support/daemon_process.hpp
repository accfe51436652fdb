#pragma once
// The real hystbenchd as a child process, and a raw socket client, for integration tests
// (tests/daemon/hystbenchd_integration_test.cpp, abuse_test.cpp).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/cli/remote/bench_client.hpp"

extern char** environ;

namespace hystbench::testing {

class Daemon {
 public:
  /// Starts hystbenchd with `config` (default config/loopback.toml) and its socket, logs and
  /// models in `dir`; returns once the socket answers (check running()).
  /// `wrapper`: a command the daemon runs under (its argv comes after it), e.g. unshare; the
  /// wrapper is looked up in PATH.
  explicit Daemon(const std::filesystem::path& dir, std::string config = {},
                  std::vector<std::string> wrapper = {})
      : dir_(dir) {
    std::filesystem::create_directories(dir_);
    socket_ = (dir_ / "s.sock").string();
    const std::string bin = std::string(HYSTBENCH_BIN_DIR) + "/hystbenchd";
    if (config.empty()) config = std::string(HYSTBENCH_SOURCE_DIR) + "/config/loopback.toml";
    const std::string logs = (dir_ / "logs").string(), models = (dir_ / "models").string();
    const std::string out = (dir_ / "daemon.log").string();  // appended: restarts keep it
    std::vector<std::string> args{bin,         "--config", config,        "--socket", socket_,
                                  "--log-dir", logs,       "--model-dir", models};
    args.insert(args.begin(), wrapper.begin(), wrapper.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    if (posix_spawnp(&pid_, args.front().c_str(), &fa, nullptr, argv.data(), environ) != 0) {
      pid_ = -1;
    }
    posix_spawn_file_actions_destroy(&fa);
    for (int i = 0; i < 200 && pid_ > 0; ++i) {
      if (std::filesystem::exists(socket_)) {
        try {
          cli::BenchClient probe(socket_);
          return;
        } catch (const cli::ClientError&) {
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
  pid_t pid() const { return pid_; }
  bool running() const { return pid_ > 0 && ::kill(pid_, 0) == 0; }

 private:
  std::filesystem::path dir_;
  std::string socket_;
  pid_t pid_ = -1;
};

/// A raw connection for sending arbitrary bytes.
class RawClient {
 public:
  explicit RawClient(const std::string& path, bool read_greeting = true) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    if (read_greeting) line();
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  int fd() const { return fd_; }
  void send(const std::string& bytes) {
    std::size_t off = 0;
    while (off < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return;
      off += static_cast<std::size_t>(n);
    }
  }
  // Next line that is not an event.
  nlohmann::json line() {
    for (;;) {
      const auto nl = buf_.find('\n');
      if (nl != std::string::npos) {
        nlohmann::json j = nlohmann::json::parse(buf_.substr(0, nl));
        buf_.erase(0, nl + 1);
        if (j.contains("event")) continue;
        return j;
      }
      char c[4096];
      const ssize_t n = ::recv(fd_, c, sizeof c, 0);
      if (n <= 0) return nlohmann::json();
      buf_.append(c, static_cast<std::size_t>(n));
    }
  }

 private:
  int fd_ = -1;
  std::string buf_;
};

/// Waits for the run.finished event of `run_id` on `c`; its result, or null after `seconds`.
inline nlohmann::json wait_finished(cli::BenchClient& c, const std::string& run_id,
                                    int seconds = 120) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < until) {
    auto e = c.next_event(std::chrono::milliseconds(500));
    if (e && (*e)["event"] == "run.finished" && (*e)["result"]["run_id"] == run_id) {
      return (*e)["result"];
    }
  }
  return nlohmann::json();
}

}  // namespace hystbench::testing
