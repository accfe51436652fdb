#include "hystbench/daemon/service/socket_server.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace hd = hystbench::daemon;
namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

fs::path unique_socket_path() {
  static std::atomic<int> counter{0};
  return fs::temp_directory_path() / ("hbsock-" + std::to_string(::getpid()) + "-" +
                                      std::to_string(counter.fetch_add(1)) + ".sock");
}

// A blocking client with a receive timeout, so a missing reply fails instead of hanging.
class TestClient {
 public:
  explicit TestClient(const fs::path& path, std::chrono::seconds timeout = 10s) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    timeval tv{static_cast<time_t>(timeout.count()), 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  }
  ~TestClient() { close(); }
  TestClient(const TestClient&) = delete;
  TestClient& operator=(const TestClient&) = delete;

  bool connected() const { return connected_; }
  int fd() const { return fd_; }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  bool send_raw(std::string_view data) {
    while (!data.empty()) {
      const ssize_t n = ::send(fd_, data.data(), data.size(), MSG_NOSIGNAL);
      if (n <= 0) return false;
      data.remove_prefix(static_cast<std::size_t>(n));
    }
    return true;
  }
  bool send(const json& j) { return send_raw(j.dump() + "\n"); }
  /// The next line without '\n'; nullopt at end of stream or timeout.
  std::optional<std::string> read_line() {
    for (;;) {
      const auto nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return line;
      }
      char chunk[65536];
      const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
      if (n <= 0) return std::nullopt;
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }
  json read_json() {
    const auto line = read_line();
    return line ? json::parse(*line) : json();
  }
  json request(const json& j) {
    send(j);
    return read_json();
  }
  /// Reads and checks the greeting.
  bool greeted() { return read_json().value("hello", "") == "hystbenchd"; }

 private:
  int fd_ = -1;
  bool connected_ = false;
  std::string buffer_;
};

hd::Reply dispatch(const hd::Request& r) {
  if (r.cmd == "echo") return hd::Reply::success({{"params", r.params}, {"client", r.client}});
  if (r.cmd == "fail") return hd::Reply::failure("nope", "asked to fail");
  if (r.cmd == "throw") throw std::runtime_error("dispatcher exploded");
  if (r.cmd == "big") return hd::Reply::success({{"data", std::string(r.params["n"], 'x')}});
  return hd::Reply::failure("unknown_cmd", "unknown command '" + r.cmd + "'");
}

class SocketServerTest : public ::testing::Test {
 protected:
  void SetUp() override { start(); }
  void TearDown() override {
    server_.reset();
    fs::remove(path_);
  }
  void start(hd::SocketServerOptions options = {}) {
    server_.reset();
    if (path_.empty()) path_ = unique_socket_path();
    options.path = path_;
    server_ = std::make_unique<hd::SocketServer>(options, dispatch);
    server_->start();
  }
  // Waits (bounded) for a condition that the event thread brings about.
  template <typename F>
  bool eventually(F condition) {
    const auto give_up = std::chrono::steady_clock::now() + 10s;
    while (!condition()) {
      if (std::chrono::steady_clock::now() > give_up) return false;
      std::this_thread::sleep_for(2ms);
    }
    return true;
  }
  fs::path path_;
  std::unique_ptr<hd::SocketServer> server_;
};

}  // namespace

TEST_F(SocketServerTest, GreetsWithNameVersionAndProtocol) {
  TestClient c(path_);
  ASSERT_TRUE(c.connected());
  const json hello = c.read_json();
  EXPECT_EQ(hello["hello"], "hystbenchd");
  EXPECT_EQ(hello["version"], HYSTBENCH_VERSION);
  EXPECT_EQ(hello["protocol"], hd::kProtocolVersion);
}

TEST_F(SocketServerTest, SocketFileHasMode0660AndIsRemovedOnStop) {
  struct stat st {};
  ASSERT_EQ(::stat(path_.c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0660u);
  server_->stop();
  EXPECT_FALSE(fs::exists(fs::symlink_status(path_)));
  server_->stop();  // idempotent
}

TEST_F(SocketServerTest, RequestsRoundTripWithTheirIds) {
  TestClient c(path_);
  ASSERT_TRUE(c.greeted());
  json r = c.request({{"id", 7}, {"cmd", "echo"}, {"params", {{"a", 1.5}}}});
  EXPECT_EQ(r["id"], 7);
  EXPECT_EQ(r["ok"], true);
  EXPECT_EQ(r["result"]["params"]["a"], 1.5);
  r = c.request({{"id", "abc"}, {"cmd", "echo"}});
  EXPECT_EQ(r["id"], "abc");
  EXPECT_EQ(r["result"]["params"], json::object());
  r = c.request({{"cmd", "echo"}});
  EXPECT_TRUE(r["id"].is_null());
  EXPECT_EQ(r["ok"], true);
  r = c.request({{"id", 8}, {"cmd", "fail"}});
  EXPECT_EQ(
      r, json::parse(R"({"id":8,"ok":false,"error":{"code":"nope","message":"asked to fail"}})"));
  r = c.request({{"id", 9}, {"cmd", "throw"}});
  EXPECT_EQ(r["error"]["code"], "internal");
  EXPECT_EQ(r["error"]["message"], "dispatcher exploded");
  r = c.request({{"id", 10}, {"cmd", "nosuch"}});
  EXPECT_EQ(r["error"]["code"], "unknown_cmd");
}

// The disconnect handler hears the number of every connection that goes: one that closes, and
// at stop() the ones still open; the error details travel as extra keys of the error object.
TEST_F(SocketServerTest, TheDisconnectHandlerHearsEveryClientThatGoes) {
  std::mutex m;
  std::vector<std::uint64_t> gone;
  server_.reset();
  hd::SocketServerOptions options;
  options.path = path_;
  server_ = std::make_unique<hd::SocketServer>(
      options,
      [](const hd::Request& r) {
        if (r.cmd == "detail") return hd::Reply::failure("bad", "no", {{"sample", 12}});
        return dispatch(r);
      },
      [&](std::uint64_t client) {
        std::lock_guard lock(m);
        gone.push_back(client);
      });
  server_->start();
  TestClient a(path_), b(path_);
  ASSERT_TRUE(a.greeted());
  ASSERT_TRUE(b.greeted());
  const auto id_a = a.request({{"cmd", "echo"}})["result"]["client"].get<std::uint64_t>();
  const auto id_b = b.request({{"cmd", "echo"}})["result"]["client"].get<std::uint64_t>();
  EXPECT_EQ(b.request({{"cmd", "detail"}})["error"],
            json::parse(R"({"code":"bad","message":"no","sample":12})"));
  a.close();
  ASSERT_TRUE(eventually([&] {
    std::lock_guard lock(m);
    return gone.size() == 1;
  }));
  EXPECT_EQ(gone.front(), id_a);
  server_->stop();
  std::lock_guard lock(m);
  EXPECT_EQ(gone, (std::vector<std::uint64_t>{id_a, id_b}));
}

TEST_F(SocketServerTest, EveryBadInputGetsItsErrorAndTheConnectionStaysUsable) {
  TestClient c(path_);
  ASSERT_TRUE(c.greeted());
  const auto error_of = [&](std::string_view raw) {
    c.send_raw(raw);
    const json r = c.read_json();
    EXPECT_EQ(r["ok"], false) << raw;
    EXPECT_TRUE(r["error"]["message"].is_string()) << raw;
    return std::make_pair(r["error"].value("code", ""), r["id"]);
  };
  EXPECT_EQ(error_of("this is not json\n").first, "bad_json");
  EXPECT_EQ(error_of("{\"cmd\": \"echo\"\n").first, "bad_json");
  EXPECT_EQ(error_of("{\"cmd\": \"\xff\xfe\"}\n").first, "bad_json");  // invalid UTF-8
  EXPECT_EQ(error_of("{\"cmd\": \"\xc3\"}\n").first, "bad_json");      // truncated sequence
  EXPECT_EQ(error_of("[1, 2]\n").first, "bad_request");
  EXPECT_EQ(error_of("\"status\"\n").first, "bad_request");
  EXPECT_EQ(error_of("{\"id\": 3}\n"), std::make_pair(std::string("bad_request"), json(3)));
  EXPECT_EQ(error_of("{\"id\": 4, \"cmd\": 5}\n").first, "bad_request");
  EXPECT_EQ(error_of("{\"id\": 5, \"cmd\": \"\"}\n").first, "bad_request");
  EXPECT_EQ(error_of("{\"id\": 6, \"cmd\": \"echo\", \"params\": [1]}\n").second, json(6));
  EXPECT_EQ(error_of("{\"id\": [1], \"cmd\": \"echo\"}\n"),
            std::make_pair(std::string("bad_request"), json(nullptr)));
  EXPECT_EQ(error_of("{\"id\": 7, \"cmd\": \"echo\", \"parms\": {}}\n").first, "bad_request");
  // Blank lines are ignored; CRLF line ends are accepted; UTF-8 in strings is kept.
  c.send_raw("\n  \r\n");
  const json ok =
      c.request(json::parse("{\"id\": 8, \"cmd\": \"echo\", \"params\": {\"s\": \"\xc2\xb5m\"}}"));
  EXPECT_EQ(ok["result"]["params"]["s"], "\xc2\xb5m");
  c.send_raw("{\"id\": 9, \"cmd\": \"echo\"}\r\n");
  EXPECT_EQ(c.read_json()["id"], 9);
  EXPECT_EQ(server_->counters().protocol_errors, 12u);
}

TEST_F(SocketServerTest, OversizeLineIsRefusedAndItsRestDiscarded) {
  TestClient c(path_);
  ASSERT_TRUE(c.greeted());
  // Past the limit in pieces, so the server sees it grow past it before the newline arrives.
  const std::size_t kLimit = hd::SocketServerOptions{}.max_line_bytes;
  const std::string piece(64 * 1024, 'a');
  for (std::size_t sent = 0; sent <= kLimit + piece.size(); sent += piece.size()) {
    ASSERT_TRUE(c.send_raw(piece));
  }
  c.send_raw("\n");
  c.send({{"id", 1}, {"cmd", "echo"}});
  json r = c.read_json();
  EXPECT_TRUE(r["id"].is_null());
  EXPECT_EQ(r["ok"], false);
  EXPECT_EQ(r["error"]["code"], "line_too_long");
  r = c.read_json();  // the rest of the long line produced nothing; the next request works
  EXPECT_EQ(r["id"], 1);
  EXPECT_EQ(r["ok"], true);

  // An over-long line that arrives whole, then a line of exactly the limit (accepted).
  c.send_raw(std::string(kLimit + 1, 'b') + "\n");
  EXPECT_EQ(c.read_json()["error"]["code"], "line_too_long");
  std::string exact = R"({"id":2,"cmd":"echo"})";
  exact += std::string(kLimit - exact.size(), ' ');
  c.send_raw(exact + "\n");
  EXPECT_EQ(c.read_json()["id"], 2);
}

TEST_F(SocketServerTest, FloodOfTenThousandRequestsIsAnsweredInOrder) {
  TestClient c(path_);
  ASSERT_TRUE(c.greeted());
  constexpr int kRequests = 10'000;
  std::thread writer([&] {
    std::string batch;
    for (int i = 0; i < kRequests; ++i) {
      batch += R"({"id":)" + std::to_string(i) + R"(,"cmd":"echo","params":{"k":)" +
               std::to_string(i) + "}}\n";
      if (batch.size() > 32 * 1024) {
        c.send_raw(batch);
        batch.clear();
      }
    }
    c.send_raw(batch);
  });
  int in_order = 0;
  for (int i = 0; i < kRequests; ++i) {
    const json r = c.read_json();
    if (r.is_object() && r["id"] == i && r["result"]["params"]["k"] == i) ++in_order;
    if (r.is_null()) break;
  }
  writer.join();
  EXPECT_EQ(in_order, kRequests);
  EXPECT_EQ(server_->counters().requests, static_cast<std::uint64_t>(kRequests));
}

TEST_F(SocketServerTest, HalfClosedClientStillGetsItsReplies) {
  TestClient c(path_);
  c.send_raw(R"({"id":1,"cmd":"echo"})"
             "\n"
             R"({"id":2,"cmd":"echo"})");  // last without '\n'
  ::shutdown(c.fd(), SHUT_WR);
  EXPECT_TRUE(c.greeted());
  EXPECT_EQ(c.read_json()["id"], 1);
  EXPECT_EQ(c.read_json()["id"], 2);
  EXPECT_FALSE(c.read_line().has_value());  // then the server closes
}

TEST_F(SocketServerTest, EventsReachEveryClient) {
  TestClient a(path_);
  TestClient b(path_);
  ASSERT_TRUE(a.greeted());
  ASSERT_TRUE(b.greeted());
  ASSERT_TRUE(eventually([&] { return server_->counters().clients == 2; }));
  server_->broadcast_event({{"event", "run.finished"}, {"run_id", "r1"}});
  const json ea = a.read_json();
  EXPECT_EQ(ea["event"], "run.finished");
  EXPECT_FALSE(ea.contains("id"));
  EXPECT_EQ(b.read_json()["run_id"], "r1");
}

TEST_F(SocketServerTest, ClientThatNeverReadsIsDisconnectedWithoutBlockingOthers) {
  hd::SocketServerOptions options;
  options.max_output_bytes = 128 * 1024;
  start(options);
  TestClient sleeper(path_);  // connects and never reads
  TestClient reader(path_);
  ASSERT_TRUE(reader.greeted());
  ASSERT_TRUE(eventually([&] { return server_->counters().clients == 2; }));
  const json event = {{"event", "progress"}, {"pad", std::string(4000, 'p')}};
  constexpr int kEvents = 500;  // 2 MB: more than the kernel buffers plus 128 KiB
  std::atomic<int> received{0};
  std::thread reading([&] {
    for (int i = 0; i < kEvents; ++i) {
      if (reader.read_json()["event"] != "progress") break;
      ++received;
    }
  });
  for (int i = 0; i < kEvents; ++i) {
    server_->broadcast_event(event);
    // Paced like real progress events: the reader keeps up, only the sleeper falls behind.
    if (i % 8 == 7 && !eventually([&] { return received.load() > i - 8; })) break;
  }
  reading.join();
  EXPECT_EQ(received.load(), kEvents);
  EXPECT_TRUE(eventually([&] { return server_->counters().slow_dropped == 1; }));
  EXPECT_TRUE(eventually([&] { return server_->counters().clients == 1; }));
  EXPECT_EQ(reader.request({{"id", 1}, {"cmd", "echo"}})["ok"], true);
  // The sleeper finds the connection closed after whatever had been sent.
  std::size_t lines = 0;
  while (sleeper.read_line()) ++lines;
  EXPECT_LT(lines, static_cast<std::size_t>(kEvents));
}

TEST_F(SocketServerTest, ClientKilledMidStreamDoesNotDisturbTheServer) {
  for (int round = 0; round < 20; ++round) {
    TestClient c(path_);
    std::string flood;
    for (int i = 0; i < 2000; ++i)
      flood += R"({"id":1,"cmd":"big","params":{"n":1000}})"
               "\n";
    c.send_raw(flood);
    // Reset instead of a clean close: SO_LINGER 0 would be TCP only; closing with unread data
    // makes the server's next send fail with EPIPE / ECONNRESET.
    c.close();
  }
  TestClient after(path_);
  ASSERT_TRUE(after.greeted());
  EXPECT_EQ(after.request({{"id", 5}, {"cmd", "echo"}})["id"], 5);
  EXPECT_TRUE(eventually([&] { return server_->counters().clients == 1; }));
}

TEST_F(SocketServerTest, ProcessKilledWhileFloodingDoesNotDisturbTheServer) {
  // Everything the child needs is prepared before fork(): it only makes system calls.
  std::string flood;
  for (int i = 0; i < 500; ++i)
    flood += R"({"id":1,"cmd":"big","params":{"n":2000}})"
             "\n";
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path_.c_str(), sizeof addr.sun_path - 1);
  const std::uint64_t before = server_->counters().requests;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) ::_exit(1);
    for (;;) {  // never reads: blocks once the server applies back-pressure, until killed
      if (::send(fd, flood.data(), flood.size(), MSG_NOSIGNAL) < 0) ::_exit(2);
    }
  }
  const bool busy = eventually([&] { return server_->counters().requests > before + 100; });
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(busy);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(eventually([&] { return server_->counters().clients == 0; }));
  TestClient after(path_);
  ASSERT_TRUE(after.greeted());
  EXPECT_EQ(after.request({{"id", 6}, {"cmd", "echo"}})["id"], 6);
}

TEST_F(SocketServerTest, HundredConcurrentClientsAllGetTheirReplies) {
  constexpr int kClients = 100;
  constexpr int kEach = 20;
  std::atomic<int> correct{0};
  std::vector<std::thread> threads;
  for (int k = 0; k < kClients; ++k) {
    threads.emplace_back([&, k] {
      TestClient c(path_);
      if (!c.greeted()) return;
      for (int i = 0; i < kEach; ++i) {
        const json r = c.request({{"id", k * 1000 + i}, {"cmd", "echo"}, {"params", {{"k", k}}}});
        if (r.is_object() && r["id"] == k * 1000 + i && r["result"]["params"]["k"] == k) {
          ++correct;
        }
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(correct.load(), kClients * kEach);
  EXPECT_EQ(server_->counters().accepted, static_cast<std::uint64_t>(kClients));
}

TEST_F(SocketServerTest, ClientsBeyondTheMaximumAreTurnedAway) {
  hd::SocketServerOptions options;
  options.max_clients = 2;
  start(options);
  TestClient a(path_);
  TestClient b(path_);
  ASSERT_TRUE(a.greeted());
  ASSERT_TRUE(b.greeted());
  TestClient c(path_);
  const json r = c.read_json();
  EXPECT_EQ(r["error"]["code"], "too_many_clients");
  EXPECT_FALSE(c.read_line().has_value());
  EXPECT_EQ(server_->counters().refused, 1u);
  a.close();
  ASSERT_TRUE(eventually([&] { return server_->counters().clients == 1; }));
  TestClient d(path_);
  EXPECT_TRUE(d.greeted());
}

TEST_F(SocketServerTest, StaleSocketIsReplacedButALiveServerOrAFileIsNot) {
  // A second server on the same path while the first is alive: refused, first unharmed.
  hd::SocketServer second({path_}, dispatch);
  EXPECT_THROW(second.start(), hd::SocketServerError);
  {
    TestClient c(path_);
    EXPECT_TRUE(c.greeted());
  }
  // Leave a stale socket file behind (a bound socket closed without unlink).
  server_.reset();
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path_.c_str(), sizeof addr.sun_path - 1);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ::close(fd);
  ASSERT_TRUE(fs::is_socket(path_));
  start();
  TestClient c(path_);
  EXPECT_TRUE(c.greeted());
  server_.reset();
  // A regular file at the path is never removed.
  std::ofstream(path_) << "precious";
  hd::SocketServer third({path_}, dispatch);
  EXPECT_THROW(third.start(), hd::SocketServerError);
  EXPECT_TRUE(fs::is_regular_file(path_));
}

TEST_F(SocketServerTest, DispatcherMayStopTheServer) {
  server_.reset();
  hd::SocketServer* self = nullptr;
  hd::SocketServer server({path_}, [&](const hd::Request& r) {
    if (r.cmd == "shutdown") self->stop();
    return hd::Reply::success();
  });
  self = &server;
  server.start();
  TestClient c(path_);
  ASSERT_TRUE(c.greeted());
  EXPECT_EQ(c.request({{"id", 1}, {"cmd", "shutdown"}})["id"], 1);
  EXPECT_FALSE(c.read_line().has_value());  // closed by the server
  server.stop();
  EXPECT_FALSE(fs::exists(fs::symlink_status(path_)));
}
