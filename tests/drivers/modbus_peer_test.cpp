// The Modbus DAQ driver against independent peers from Debian, started here on 127.0.0.1:
// a pymodbus server (python3-pymodbus), mbpoll reading hystbench-simdaq, and RTU over a socat
// pseudo-terminal pair. A test whose peer is not installed skips, naming the package.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/io_thread_driver.hpp"
#include "hystbench/drivers/modbus_daq.hpp"
#include "hystbench/drivers/simdaq_register_map.hpp"
#include "peer_process.hpp"
#include "pymodbus_peer.hpp"

namespace hd = hystbench::drivers;
namespace ht = hystbench::test;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

#define REQUIRE_PROGRAM(name, package)                                    \
  if (ht::find_program(name).empty())                                     \
  GTEST_SKIP() << name << " is not installed (Debian package " << package \
               << ", scripts/deps.sh test installs it)"

}  // namespace

TEST(ModbusPeer, WritesAndReadsSixteenBitRegistersOfAPymodbusServer) {
  REQUIRE_PYMODBUS();
  ht::PymodbusPeer peer({"--echo", "0:1:10"});  // what lands in HR 0 shows up in IR 10
  ASSERT_GT(peer.port, 0) << "the pymodbus peer did not start";
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  const json params = {{"port", peer.port},
                       {"io", "loop"},
                       {"output", {{"address", 0}}},
                       {"measurement", {{"table", "input"}, {"address", 10}, {"scale", 0.001}}}};
  ASSERT_TRUE(d.configure(params, 100.0).ok);
  const auto act = d.activate();
  ASSERT_TRUE(act.ok) << act.message;
  ASSERT_EQ(d.write(75.0), hd::DriverStatus::kOk);
  // 75 V of 150 V over 16 bits: code 32768 (rounded), written with function 6 to register 0.
  const json w = peer.wait_write(32768);
  ASSERT_FALSE(w.is_null());
  EXPECT_EQ(w["fc"], 6);
  EXPECT_EQ(w["address"], 0);
  hd::Measurement m;
  ASSERT_EQ(d.read(m), hd::DriverStatus::kOk);
  EXPECT_DOUBLE_EQ(m.position_um, 32.768);  // the echo, 1 nm per count
  EXPECT_EQ(m.age_ticks, 0u);
  EXPECT_EQ(m.response_ticks, 0u);  // io = "loop": the read follows this tick's write
  EXPECT_DOUBLE_EQ(d.measurement_resolution_um(), 0.001);
  EXPECT_TRUE(d.deactivate().ok);
  // Deactivation leaves the safe output (0 V) in the register.
  EXPECT_FALSE(peer.wait_write(0).is_null());
}

TEST(ModbusPeer, FunctionTwentyThreeWithSignedThirtyTwoBitWordOrders) {
  REQUIRE_PYMODBUS();
  // Measurement preset: s32 -16 high word first at HR 30-31.
  ht::PymodbusPeer peer({"--hr", "30=0xffff,31=0xfff0"});
  ASSERT_GT(peer.port, 0);
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  const json params = {
      {"port", peer.port},
      {"io", "loop"},
      {"write_read", true},
      {"output",
       {{"address", 20},
        {"format", "s32"},
        {"word_order", "little"},
        {"scale", 0.001},
        {"min_v", -10.0},
        {"max_v", 10.0}}},
      {"measurement", {{"table", "holding"}, {"address", 30}, {"format", "s32"}, {"scale", 0.5}}}};
  ASSERT_TRUE(d.configure(params, 100.0).ok);
  ASSERT_TRUE(d.activate().ok);
  ASSERT_EQ(d.write(-2.5), hd::DriverStatus::kOk);
  hd::Measurement m;
  ASSERT_EQ(d.read(m), hd::DriverStatus::kOk);
  EXPECT_DOUBLE_EQ(m.position_um, -8.0);
  // -2500 mV = 0xfffff63c, low word first, in one function-23 transaction.
  const json w = peer.wait_write(0xf63c);
  ASSERT_FALSE(w.is_null());
  EXPECT_EQ(w["fc"], 23);
  EXPECT_EQ(w["address"], 20);
  EXPECT_EQ(w["values"], json({0xf63c, 0xffff}));
  d.deactivate();
}

TEST(ModbusPeer, ActivationNamesTheRegisterTheDeviceRefuses) {
  REQUIRE_PYMODBUS();
  ht::PymodbusPeer peer({"--size", "16"});
  ASSERT_GT(peer.port, 0);
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  ASSERT_TRUE(d.configure({{"port", peer.port}, {"measurement", {{"address", 40}}}}, 1000.0).ok);
  const auto r = d.activate();
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.message.find("reading input register 40"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("Illegal data address"), std::string::npos) << r.message;
}

TEST(ModbusPeer, IoThreadDeliversFreshValuesAndFaultsWhenThePeerDies) {
  REQUIRE_PYMODBUS();
  ht::PymodbusPeer peer({"--echo", "0:1:10"});
  ASSERT_GT(peer.port, 0);
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  const json params = {{"port", peer.port},
                       {"io", "thread"},
                       {"max_stale_reads", 400},
                       {"max_failed_transactions", 2},
                       {"reconnect_interval_ms", 50},
                       {"measurement", {{"table", "input"}, {"address", 10}, {"scale", 0.001}}}};
  ASSERT_TRUE(d.configure(params, 1000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  // Ticks at 1 kHz: the value written comes back through the peer's echo.
  hd::Measurement m;
  bool seen = false;
  std::uint64_t stale = 0;
  for (int k = 0; k < 3000 && !seen; ++k) {
    ASSERT_EQ(d.write(30.0), hd::DriverStatus::kOk);
    const auto s = d.read(m);
    ASSERT_TRUE(s == hd::DriverStatus::kOk || s == hd::DriverStatus::kStale) << to_string(s);
    if (s == hd::DriverStatus::kStale) {
      ++stale;
      EXPECT_GT(m.age_ticks, 0u);
    }
    seen = s == hd::DriverStatus::kOk && std::abs(m.position_um - 13.107) < 1e-9;
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(seen) << d.diagnostics().dump();
  EXPECT_EQ(d.diagnostics()["stale_reads"], stale);
  EXPECT_GT(d.diagnostics()["rtt_us"]["count"].get<int>(), 0);

  peer.proc->kill();
  hd::DriverStatus s = hd::DriverStatus::kOk;
  for (int k = 0; k < 2000 && s != hd::DriverStatus::kFault; ++k) {
    d.write(30.0);
    s = d.read(m);
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_EQ(s, hd::DriverStatus::kFault);
  const json diag = d.diagnostics();
  EXPECT_FALSE(diag["connected"].get<bool>());
  EXPECT_NE(diag["last_error"].get<std::string>().find("connecting to tcp 127.0.0.1:"),
            std::string::npos)
      << diag.dump();
  EXPECT_NE(diag["last_fault"].get<std::string>().find("in a row"), std::string::npos);
  // The framework called on_error() in the read that reported the fault: the safe output is
  // the I/O thread's command from that tick on.
  EXPECT_EQ(diag["output_v"].get<double>(), 0.0);
  EXPECT_EQ(d.safe_state(), hd::DriverStatus::kOk);
  EXPECT_EQ(d.diagnostics()["output_v"].get<double>(), 0.0);
  d.deactivate();
}

TEST(ModbusPeer, MbpollReadsAndWritesHystbenchSimdaq) {
  REQUIRE_PROGRAM("mbpoll", "mbpoll");
  ht::PeerProcess simdaq({ht::bin("hystbench-simdaq"), "--port", "0"});
  const auto line = simdaq.wait_for("listening on tcp", 10s);
  ASSERT_TRUE(line) << "hystbench-simdaq did not start";
  const std::string port = line->substr(line->rfind(':') + 1);
  const auto mbpoll = [&](std::vector<std::string> args) {
    std::vector<std::string> argv{
        ht::find_program("mbpoll"), "-m", "tcp", "-p", port, "-0", "-1", "-o", "2"};
    argv.insert(argv.end(), args.begin(), args.end());
    return ht::run_program(argv, 10s);
  };
  auto [rc, out] = mbpoll({"-t", "3", "-r", "7", "-c", "2", "127.0.0.1"});
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("[7]: \t18498"), std::string::npos) << out;  // 0x4842 "HB"
  EXPECT_NE(out.find("[8]: \t1"), std::string::npos) << out;
  // 100 V as s32 millivolts, high word first, to HR 1-2; the DAC-code view follows.
  std::tie(rc, out) = mbpoll({"-t", "4:int", "-B", "-r", "1", "127.0.0.1", "100000"});
  ASSERT_EQ(rc, 0) << out;
  std::tie(rc, out) = mbpoll({"-t", "3", "-r", "5", "127.0.0.1"});
  EXPECT_NE(out.find("[5]: \t43690"), std::string::npos) << out;  // 100/150 * 65535
  std::this_thread::sleep_for(100ms);                             // the plant settles
  std::tie(rc, out) = mbpoll({"-t", "3:int", "-B", "-r", "1", "127.0.0.1"});
  ASSERT_EQ(rc, 0) << out;
  const auto colon = out.find("[1]:");
  ASSERT_NE(colon, std::string::npos) << out;
  const double nm = std::stod(out.substr(colon + 5));
  EXPECT_GT(nm, 15000.0) << out;  // 100 V lifts the stack by tens of micrometres
  EXPECT_LT(nm, 60000.0) << out;
  // The communication watchdog: 50 ms without an output write drops the output to 0 V.
  std::tie(rc, out) = mbpoll({"-t", "4", "-r", "3", "127.0.0.1", "50"});
  ASSERT_EQ(rc, 0) << out;
  std::this_thread::sleep_for(150ms);
  std::tie(rc, out) = mbpoll({"-t", "3", "-r", "5", "-c", "2", "127.0.0.1"});
  EXPECT_NE(out.find("[5]: \t0\n"), std::string::npos) << out;
  EXPECT_NE(out.find("[6]: \t1\n"), std::string::npos) << out;  // status: watchdog tripped
}

TEST(ModbusPeer, RtuOverASocatPseudoTerminalPair) {
  REQUIRE_PROGRAM("socat", "socat");
  const auto dir =
      std::filesystem::temp_directory_path() / ("hystbench_rtu_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string daq = (dir / "daq").string(), bench = (dir / "bench").string();
  ht::PeerProcess socat({ht::find_program("socat"), "-d", "-d", "pty,raw,echo=0,link=" + daq,
                         "pty,raw,echo=0,link=" + bench},
                        -1, /*keep_stderr=*/false);  // socat -d -d reports on stderr
  ASSERT_TRUE(socat.wait_for("starting data transfer loop", 10s)) << "socat did not start";
  ht::PeerProcess simdaq(
      {ht::bin("hystbench-simdaq"), "--rtu", daq, "--baud", "115200", "--slave-id", "7"});
  ASSERT_TRUE(simdaq.wait_for("serving rtu", 10s));

  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  const json params = {
      {"transport", "rtu"},
      {"device", bench},
      {"baud", 115200},
      {"slave_id", 7},
      {"response_timeout_ms", 200},
      {"io", "loop"},
      {"write_read", true},
      {"output", {{"address", 1}, {"format", "s32"}, {"scale", 0.001}}},
      {"measurement",
       {{"table", "holding"}, {"address", 11}, {"format", "s32"}, {"scale", 0.001}}}};
  // 115200 baud 8N1: a function-23 tick needs about 2.9 ms on the wire.
  const auto refused = d.configure(params, 1000.0);
  ASSERT_FALSE(refused.ok);
  EXPECT_NE(refused.message.find("at most 349 Hz"), std::string::npos) << refused.message;
  ASSERT_TRUE(d.configure(params, 200.0).ok);
  const auto act = d.activate();
  ASSERT_TRUE(act.ok) << act.message;
  hd::Measurement m;
  ASSERT_EQ(d.read(m), hd::DriverStatus::kOk);
  const double y0 = m.position_um;
  for (int k = 0; k < 20; ++k) {
    ASSERT_EQ(d.write(120.0), hd::DriverStatus::kOk);
    ASSERT_EQ(d.read(m), hd::DriverStatus::kOk) << d.diagnostics().dump();
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_GT(m.position_um - y0, 20.0) << "y0 " << y0 << " y " << m.position_um;
  EXPECT_EQ(d.diagnostics()["failed_transactions"], 0);
  ASSERT_TRUE(d.deactivate().ok);

  // mbpoll on the same line (the driver has let go of it).
  if (!ht::find_program("mbpoll").empty()) {
    auto [rc, out] =
        ht::run_program({ht::find_program("mbpoll"), "-m", "rtu", "-b", "115200", "-P", "none",
                         "-a", "7", "-0", "-1", "-t", "3", "-r", "5", "-c", "3", bench},
                        10s);
    EXPECT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("[5]: \t0"), std::string::npos) << out;  // safe output after deactivate
    EXPECT_NE(out.find("[7]: \t18498"), std::string::npos) << out;
  }
  simdaq.kill();
  socat.kill();
  std::filesystem::remove_all(dir);
}
