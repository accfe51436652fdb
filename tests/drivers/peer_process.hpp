#pragma once
// Test helper: a peer program started by the test itself (posix_spawn), its stdout read line by
// line with a deadline, killed and reaped when the object goes. Also finding programs on PATH
// and the project's own binaries (HYSTBENCH_BIN_DIR).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

extern char** environ;

namespace hystbench::test {

/// Full path of `name` on PATH (or the absolute path itself), or empty.
inline std::string find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) {
    return ::access(name.c_str(), X_OK) == 0 ? name : std::string();
  }
  const char* path = std::getenv("PATH");
  std::string p = path ? path : "/usr/bin:/bin";
  for (std::size_t start = 0; start <= p.size();) {
    const std::size_t end = p.find(':', start);
    const std::string dir = p.substr(start, end == std::string::npos ? end : end - start);
    const std::string full = dir + "/" + name;
    if (!dir.empty() && ::access(full.c_str(), X_OK) == 0) return full;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return {};
}

/// A binary of this build (build/bin/NAME).
inline std::string bin(const std::string& name) {
  return (std::filesystem::path(HYSTBENCH_BIN_DIR) / name).string();
}

class PeerProcess {
 public:
  /// Starts argv[0] with its stdout (and stderr unless `keep_stderr`) on a pipe.
  /// `inherit_fd` >= 0 is passed to the child as fd 3.
  explicit PeerProcess(std::vector<std::string> argv, int inherit_fd = -1, bool keep_stderr = true)
      : argv_(std::move(argv)) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) return;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    if (!keep_stderr) posix_spawn_file_actions_adddup2(&fa, fds[1], 2);
    if (inherit_fd >= 0) posix_spawn_file_actions_adddup2(&fa, inherit_fd, 3);
    std::vector<char*> args;
    for (auto& a : argv_) args.push_back(a.data());
    args.push_back(nullptr);
    // Own process group, so kill() takes the peer's children (socat, python) along.
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attr, 0);
    if (posix_spawn(&pid_, args[0], &fa, &attr, args.data(), environ) != 0) pid_ = -1;
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    out_ = fds[0];
  }
  ~PeerProcess() {
    kill(SIGKILL);
    if (out_ >= 0) ::close(out_);
  }
  PeerProcess(const PeerProcess&) = delete;
  PeerProcess& operator=(const PeerProcess&) = delete;

  bool started() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }

  /// The next stdout line within `timeout`, or nullopt (timeout or end of output).
  std::optional<std::string> read_line(std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          until - std::chrono::steady_clock::now());
      if (left.count() <= 0 || out_ < 0) return std::nullopt;
      pollfd p{out_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char buf[4096];
      const ssize_t n = ::read(out_, buf, sizeof buf);
      if (n <= 0) return std::nullopt;
      buffer_.append(buf, static_cast<std::size_t>(n));
    }
  }
  /// The first line containing `needle` within `timeout` (earlier lines are dropped).
  std::optional<std::string> wait_for(const std::string& needle,
                                      std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          until - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      auto line = read_line(left);
      if (!line) return std::nullopt;
      if (line->find(needle) != std::string::npos) return line;
    }
  }
  /// Signals the whole process group and reaps the peer. Idempotent.
  void kill(int sig = SIGKILL) {
    if (pid_ <= 0) return;
    ::kill(-pid_, sig);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }
  /// Waits for the peer to exit by itself; its exit status, or -1 after `timeout`.
  int wait_exit(std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (pid_ > 0 && std::chrono::steady_clock::now() < until) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      ::usleep(2000);
    }
    return -1;
  }

 private:
  std::vector<std::string> argv_;
  pid_t pid_ = -1;
  int out_ = -1;
  std::string buffer_;
};

/// Runs a program to completion and returns (exit status, stdout+stderr), bounded in time.
inline std::pair<int, std::string> run_program(std::vector<std::string> argv,
                                               std::chrono::milliseconds timeout) {
  PeerProcess p(std::move(argv), -1, false);
  std::string out;
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (auto line = p.read_line(std::chrono::duration_cast<std::chrono::milliseconds>(
             until - std::chrono::steady_clock::now()))) {
    out += *line + "\n";
  }
  const int rc = p.wait_exit(std::chrono::milliseconds(500));
  return {rc, out};
}

}  // namespace hystbench::test
