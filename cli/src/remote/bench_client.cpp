#include "hystbench/cli/remote/bench_client.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace hystbench::cli {

using nlohmann::json;

BenchClient::BenchClient(const std::string& socket_path) : path_(socket_path) {
  sockaddr_un addr{};
  if (socket_path.size() >= sizeof(addr.sun_path)) {
    throw ClientError(socket_path + ": socket path too long");
  }
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw ClientError(std::string("socket: ") + std::strerror(errno));
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, socket_path.c_str(), socket_path.size() + 1);
  if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    std::string hint;
    if (e == ENOENT || e == ECONNREFUSED)
      hint = " (is hystbenchd running? start it or pass --socket)";
    if (e == EACCES) hint = " (not in the group that owns the socket?)";
    throw ClientError(socket_path + ": cannot connect: " + std::strerror(e) + hint);
  }
  auto hello = read_line(std::chrono::seconds(5));
  if (!hello || !hello->contains("hello")) {
    throw ClientError(socket_path + ": no hystbenchd greeting on this socket");
  }
  greeting_ = *hello;
}

BenchClient::~BenchClient() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<json> BenchClient::read_line(std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto nl = buffer_.find('\n');
    if (nl != std::string::npos) {
      std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      try {
        return json::parse(line);
      } catch (const json::exception& e) {  // parse_error or out_of_range (number beyond double)
        throw ClientError(path_ + ": daemon sent a malformed line: " + e.what());
      }
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    if (left.count() <= 0) return std::nullopt;
    pollfd pfd{fd_, POLLIN, 0};
    const int r = ::poll(&pfd, 1, static_cast<int>(left.count()));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) continue;
    char chunk[65536];
    const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
    if (n == 0) throw ClientError(path_ + ": the daemon closed the connection");
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      throw ClientError(path_ + ": read failed: " + std::strerror(errno));
    }
    buffer_.append(chunk, static_cast<std::size_t>(n));
  }
}

json BenchClient::request(const std::string& cmd, const json& params,
                          std::chrono::milliseconds timeout) {
  const long long id = next_id_++;
  const std::string line = json{{"id", id}, {"cmd", cmd}, {"params", params}}.dump() + "\n";
  std::size_t sent = 0;
  while (sent < line.size()) {
    const ssize_t n = ::send(fd_, line.data() + sent, line.size() - sent, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw ClientError(path_ + ": send failed: " + std::strerror(errno));
    }
    sent += static_cast<std::size_t>(n);
  }
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    if (left.count() <= 0) throw ClientError(path_ + ": no reply to '" + cmd + "' in time");
    auto msg = read_line(left);
    if (!msg) continue;
    if (msg->contains("event") && !msg->contains("id")) {
      events_.push_back(std::move(*msg));
      continue;
    }
    if (msg->value("id", json()) == json(id)) return *msg;
  }
}

std::optional<json> BenchClient::next_event(std::chrono::milliseconds timeout) {
  if (!events_.empty()) {
    json e = std::move(events_.front());
    events_.pop_front();
    return e;
  }
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    if (left.count() <= 0) return std::nullopt;
    auto msg = read_line(left);
    if (!msg) return std::nullopt;
    if (msg->contains("event")) return msg;
  }
}

}  // namespace hystbench::cli
