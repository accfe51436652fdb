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
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <tuple>
#include <utility>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/remote/bench_client.hpp"
#include "hystbench/cli/remote/remote_commands.hpp"
#include "hystbench/common/request_limits.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "support/daemon_process.hpp"
#include "support/temp_dir_test.hpp"

namespace cli = hystbench::cli;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using hystbench::testing::Daemon;
using hystbench::testing::RawClient;
using hystbench::testing::wait_finished;

class HystbenchdTest : public hystbench::test::TempDirTest {
 protected:
  HystbenchdTest() : TempDirTest("hbd") {}
  void SetUp() override {
    TempDirTest::SetUp();
    daemon_ = std::make_unique<Daemon>(dir_);
    ASSERT_TRUE(daemon_->running()) << "hystbenchd did not start";
  }
  void TearDown() override {
    daemon_.reset();
    TempDirTest::TearDown();
  }
  std::unique_ptr<Daemon> daemon_;
};

}  // namespace

TEST_F(HystbenchdTest, TrackRunFromStartToEndOverTheSocket) {
  cli::BenchClient c(daemon_->socket());
  EXPECT_EQ(c.greeting()["hello"], "hystbenchd");
  json r = c.request("track", {{"compensator", "none"}, {"periods", 2}, {"frequency_hz", 2}});
  ASSERT_TRUE(r["ok"]) << r.dump();
  EXPECT_EQ(r["id"], 1);
  const std::string run_id = r["result"]["run_id"];
  const json result = wait_finished(c, run_id);
  ASSERT_EQ(result["end"], "completed") << result.dump();
  EXPECT_EQ(result["dropped"], 0);
  const auto log = cli::DataTable::read_csv(result["log"].get<std::string>());
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
  EXPECT_EQ(code_of(std::string(hystbench::common::kMaxRequestLineBytes + 1, 'x') + "\n"),
            "line_too_long");
  EXPECT_EQ(code_of("\xff\xfe{\"cmd\":\"status\"}\n"), "bad_json");
  // The connection still works and nothing changed.
  raw.send("{\"id\":9,\"cmd\":\"status\"}\n");
  const json s = raw.line();
  EXPECT_TRUE(s["ok"]);
  EXPECT_EQ(s["result"]["state"], "idle");
  EXPECT_TRUE(s["result"]["last_result"].is_null());
  // A run while one is active.
  cli::BenchClient c(daemon_->socket());
  ASSERT_TRUE(c.request("track", {{"compensator", "none"}, {"periods", 50}})["ok"]);
  const json busy = c.request("identify");
  EXPECT_FALSE(busy["ok"]);
  EXPECT_EQ(busy["error"]["code"], "busy");
  EXPECT_TRUE(c.request("stop")["ok"]);
}

// The user's path for their own trajectory: the CLI's reader and uploader against the real
// daemon. A file that leaves the range is refused naming its line; a client gone mid-upload
// leaves nothing behind; a good file is tracked.
TEST_F(HystbenchdTest, UploadedTrajectoriesOverTheSocket) {
  {
    cli::BenchClient gone(daemon_->socket());
    ASSERT_TRUE(gone.request("upload.begin", {{"kind", "reference"}, {"samples", 100}})["ok"]);
    ASSERT_TRUE(gone.request("upload.chunk", {{"upload", "upload-1"},
                                              {"offset", 0},
                                              {"t", {0.0, 0.001}},
                                              {"values", {10.0, 10.1}}})["ok"]);
    EXPECT_EQ(gone.request("status")["result"]["uploads"]["open"], 1);
  }  // disconnects mid-upload
  cli::BenchClient c(daemon_->socket());
  json status;
  for (int i = 0; i < 200; ++i) {
    status = c.request("status")["result"];
    if (status["uploads"]["open"] == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(status["uploads"]["open"], 0);
  EXPECT_EQ(status["uploads"]["staged_samples"], 0);
  EXPECT_EQ(status["state"], "idle");

  const fs::path bad = dir_ / "bad.csv", good = dir_ / "good.csv";
  {
    std::ofstream b(bad), g(good);
    b << "# a ramp out of the 0..44 um range\nt,yr\n";
    g << "t,yr\n";
    for (int k = 0; k < 1000; ++k) {
      b << k * 1e-3 << "," << 10.0 + 40.0 * k * 1e-3 << "\n";  // 44 um passed at row 851
      g << k * 1e-3 << "," << 20.0 + 5.0 * std::sin(2.0 * M_PI * 2.0 * k * 1e-3) << "\n";
    }
  }
  cli::RemoteCommand cmd;
  cmd.socket_path = daemon_->socket();
  cmd.cmd = "track";
  cmd.params = {{"compensator", "none"}};
  cmd.upload = cli::read_upload(bad.string(), "reference", "t", "yr", 1.0, 0.0);
  std::ostringstream out, err;
  EXPECT_EQ(cli::run_remote(cmd, out, err), 1);
  EXPECT_NE(err.str().find("[out_of_range]"), std::string::npos) << err.str();
  // Data row 852 (sample 851) is on line 854: a comment and the header come first.
  EXPECT_NE(err.str().find("bad.csv:854: the first offending row"), std::string::npos) << err.str();
  EXPECT_TRUE(c.request("status")["result"]["last_result"].is_null());  // nothing ran

  cmd.upload = cli::read_upload(good.string(), "reference", "t", "yr", 1.0, 0.0);
  cmd.wait = true;
  cmd.json_output = true;
  out.str("");
  ASSERT_EQ(cli::run_remote(cmd, out, err), 0) << err.str();
  const json r = json::parse(out.str());
  EXPECT_EQ(r["end"], "completed");
  EXPECT_NEAR(r["range_um"].get<double>(), 10.0, 0.01);
  EXPECT_GT(r["rms_error_percent"].get<double>(), 0.0);
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
      cli::BenchClient c(daemon_->socket());
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
  cli::BenchClient c(daemon_->socket());
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
  cli::BenchClient c(daemon_->socket());
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
    } catch (const cli::ClientError&) {
      break;  // the daemon closed the socket
    }
    if (!e) break;
    if ((*e)["event"] == "run.finished") finished = (*e)["result"];
  }
  ASSERT_FALSE(finished.is_null());
  EXPECT_EQ(finished["end"], "aborted");
  EXPECT_EQ(finished["output_v_after"], 0.0);
  // The log is complete and readable: one row per sample, indices without gaps.
  const auto log = cli::DataTable::read_csv(log_path);
  EXPECT_EQ(log.rows(), finished["samples"].get<std::size_t>());
  const auto& index = log.column("index");
  for (std::size_t k = 0; k < index.size(); ++k) ASSERT_EQ(index[k], static_cast<double>(k));
  EXPECT_FALSE(fs::exists(daemon_->socket()));
}

// The service as its users meet it: the daemon runs where the client's folder does not exist for
// it (the unit's ProtectHome and PrivateTmp; here a mount namespace with a tmpfs over the folder).
// `hystbench model load FILE` of a model in that folder works, because the document travels;
// a request naming the path is refused.
TEST(HystbenchdService, ModelLoadWorksWhenTheDaemonCannotSeeTheClientsFolder) {
  if (std::system("unshare -Urm true > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "unprivileged mount namespaces (unshare -Urm) are not available here";
  }
  const fs::path dir = fs::temp_directory_path() / ("hbd_ns_" + std::to_string(::getpid()));
  const fs::path client = dir / "client";
  fs::create_directories(client);
  const fs::path model = client / "actuator.json";
  {
    hystbench::compensation::ActuatorModel m(std::make_unique<hystbench::compensation::PiModel>(
        hystbench::compensation::PiParameters{{0.0, 20.0, 40.0}, {0.25, 0.05, 0.03}, 0.0}));
    m.input_min = 0.0;
    m.input_max = 150.0;
    std::ofstream(model) << hystbench::compensation::to_json(
        hystbench::compensation::ModelFile{m, json::object()});
  }
  {
    // The daemon's world: a tmpfs over the client's folder (what it sees there is empty).
    Daemon daemon(dir / "daemon", {},
                  {"unshare", "-Urm", "--", "sh", "-c",
                   "mount -t tmpfs tmpfs \"$0\" && exec \"$@\"", client.string()});
    ASSERT_TRUE(daemon.running()) << "hystbenchd did not start in its namespace";
    EXPECT_FALSE(fs::exists(fs::path("/proc") / std::to_string(daemon.pid()) / "root" /
                            model.relative_path()))
        << "the daemon can see the client's file: the test would prove nothing";

    const std::string cli = std::string(HYSTBENCH_BIN_DIR) + "/hystbench --socket " +
                            daemon.socket() + " model load " + model.string() + " --json 2>&1";
    std::string output;
    FILE* p = ::popen(cli.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[512];
    while (std::fgets(buf, sizeof buf, p) != nullptr) output += buf;
    EXPECT_EQ(::pclose(p), 0) << output;
    const json loaded = json::parse(output);
    EXPECT_EQ(loaded["type"], "pi") << output;
    EXPECT_EQ(loaded["name"], "actuator.json") << output;

    cli::BenchClient c(daemon.socket());
    const json by_path = c.request("model.load", {{"path", model.string()}});
    EXPECT_FALSE(by_path["ok"].get<bool>());
    EXPECT_EQ(by_path["error"]["code"], "bad_params") << by_path.dump();
    const json stored = c.request("model.load", {{"stored", "actuator.json"}});
    EXPECT_TRUE(stored["ok"].get<bool>()) << stored.dump();
    EXPECT_EQ(c.request("status")["result"]["model"]["type"], "pi");
  }
  fs::remove_all(dir);
}

// A model identify wrote, with the frequency responses it measured (a file of 80 kB or more),
// travels in one request: `hystbench model load FILE` gives it to another daemon, which then
// designs its feedback on those responses without measuring (`tune`).
TEST(HystbenchdService, AnIdentifiedModelWithItsResponsesLoadsIntoAnotherDaemon) {
  const fs::path dir = fs::temp_directory_path() / ("hbd_models_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ifstream in(std::string(HYSTBENCH_SOURCE_DIR) + "/config/loopback.toml");
  std::stringstream toml;
  for (std::string line; std::getline(in, line);) {
    toml << line << "\n";
    if (line == "[loop]") toml << "clock = \"simulated\"\n";
  }
  const fs::path config = dir / "simulated.toml";
  std::ofstream(config) << toml.str();
  auto cli_json = [](const std::string& socket, const std::string& args) {
    const std::string cmd = std::string(HYSTBENCH_BIN_DIR) + "/hystbench --socket " + socket + " " +
                            args + " --json 2>&1";
    std::string output;
    FILE* p = ::popen(cmd.c_str(), "r");
    char buf[4096];
    while (p != nullptr && std::fgets(buf, sizeof buf, p) != nullptr) output += buf;
    const int status = p != nullptr ? ::pclose(p) : -1;
    return std::make_pair(status, output);
  };
  std::string model;
  {
    Daemon first(dir / "first", config.string());
    ASSERT_TRUE(first.running());
    const auto [status, out] = cli_json(first.socket(), "identify --wait");
    ASSERT_EQ(status, 0) << out;
    model = json::parse(out)["model"]["path"].get<std::string>();
  }
  ASSERT_GT(fs::file_size(model), 80000u) << "a model this small proves nothing about the limit";
  Daemon second(dir / "second", config.string());
  ASSERT_TRUE(second.running());
  const auto [loaded_status, loaded] = cli_json(second.socket(), "model load " + model);
  ASSERT_EQ(loaded_status, 0) << loaded;
  const auto [tune_status, tune] = cli_json(second.socket(), "tune");
  ASSERT_EQ(tune_status, 0) << tune;
  EXPECT_EQ(json::parse(tune)["gains"], "designed") << tune;
  fs::remove_all(dir);
}

namespace {

/// Runs `hystbenchd <args>`; its exit status and its output (stdout and stderr).
std::pair<int, std::string> hystbenchd(const std::string& args) {
  const std::string command = std::string(HYSTBENCH_BIN_DIR) + "/hystbenchd " + args + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, ""};
  std::string out;
  char buffer[4096];
  while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace

// --check-config shows the clock; --clock overrides it and is refused, saying why, with a driver
// that cannot follow a virtual clock; a bad [actuator] table is refused at check time, by line.
TEST(HystbenchdCheckConfig, ShowsTheClockAndRefusesWhatCannotRun) {
  const fs::path dir = fs::temp_directory_path() / ("hbd-check-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path loopback = dir / "loopback.toml";
  std::ofstream(loopback) << "[loop]\nrate_hz = 10000\n";
  const fs::path modbus = dir / "modbus.toml";
  std::ofstream(modbus) << "[driver]\ntype = \"modbus\"\n";
  const fs::path bad = dir / "bad.toml";
  std::ofstream(bad) << "[loop]\nclock = \"simulated\"\n\n[actuator.dynamics]\nenabled = true\n"
                        "mode_gains = [0.1, 0.2]\n";

  auto [status, out] = hystbenchd("--check-config -c " + loopback.string());
  ASSERT_EQ(status, 0) << out;
  EXPECT_EQ(json::parse(out)["loop"]["clock"], "wall") << out;
  std::tie(status, out) = hystbenchd("--clock simulated --check-config -c " + loopback.string());
  ASSERT_EQ(status, 0) << out;
  EXPECT_EQ(json::parse(out)["loop"]["clock"], "simulated") << out;

  std::tie(status, out) = hystbenchd("--clock simulated --check-config -c " + modbus.string());
  EXPECT_EQ(status, 2) << out;
  EXPECT_NE(out.find("--clock: \"simulated\" needs driver.type = \"loopback\""), std::string::npos)
      << out;
  std::tie(status, out) = hystbenchd("--clock virtual --check-config");
  EXPECT_NE(status, 0) << out;

  std::tie(status, out) = hystbenchd("--check-config -c " + bad.string());
  EXPECT_EQ(status, 2) << out;
  EXPECT_NE(out.find(bad.string() + ":6: actuator.dynamics.mode_gains: must sum to 1"),
            std::string::npos)
      << out;
  fs::remove_all(dir);
}
