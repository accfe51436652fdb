// hystbench-simdaq: a Modbus TCP or RTU server (libmodbus) in front of the simulated actuator,
// or of a simulated stage of several axes (one register block per axis), so the bench can run
// over real Modbus without hardware. The register map is in
// drivers/include/hystbench/drivers/simdaq_register_map.hpp and docs/drivers.md.
// The plant advances with the wall clock at --sim-rate-hz; each request first brings it up to
// now, then applies what the request wrote (sample and hold).
#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <vector>

#include "hystbench/common/run_main.hpp"
#include "hystbench/drivers/simdaq_register_map.hpp"
#include "realtime_plant.hpp"

namespace map = hystbench::drivers::simdaq;
using hystbench::apps::RealtimePlant;

namespace {

struct Server {
  RealtimePlant& plant;
  modbus_mapping_t* regs;
  int header_length = 0;
  /// Per axis: its last output write, the watchdog's trip, the output clamp.
  struct AxisState {
    std::int64_t last_write_ns = RealtimePlant::now_ns();
    bool tripped = false;
    bool clamped = false;
  };
  std::vector<AxisState> axes = std::vector<AxisState>(plant.axes());

  std::uint16_t* holding(std::size_t a) const { return regs->tab_registers + a * map::kAxisBlock; }
  std::uint16_t* input(std::size_t a) const {
    return regs->tab_input_registers + a * map::kAxisBlock;
  }
  std::uint16_t code_of(double v, std::size_t a) const {
    const double c =
        std::round((v - plant.input_min(a)) / (plant.input_max(a) - plant.input_min(a)) * 65535.0);
    return static_cast<std::uint16_t>(std::clamp(c, 0.0, 65535.0));
  }
  static void put32(std::uint16_t* r, std::int64_t v) {
    const auto bits = static_cast<std::uint32_t>(static_cast<std::uint64_t>(v) & 0xffffffffu);
    r[0] = static_cast<std::uint16_t>(bits >> 16);
    r[1] = static_cast<std::uint16_t>(bits & 0xffffu);
  }
  static std::int32_t get32(const std::uint16_t* r) {
    return static_cast<std::int32_t>((static_cast<std::uint32_t>(r[0]) << 16) | r[1]);
  }
  void show_output(std::size_t a) {
    holding(a)[map::kHrOutputCode] = code_of(plant.output_v(a), a);
    put32(&holding(a)[map::kHrOutputMv], std::llround(plant.output_v(a) * 1000.0));
    input(a)[map::kIrAppliedCode] = code_of(plant.output_v(a), a);
  }
  // Before a request: the plant up to now, the watchdogs, the measurement registers.
  void before() {
    plant.advance();
    for (std::size_t a = 0; a < axes.size(); ++a) {
      AxisState& st = axes[a];
      std::uint16_t* ir = input(a);
      std::uint16_t* hr = holding(a);
      const std::uint16_t wd = hr[map::kHrWatchdogMs];
      if (wd > 0 && !st.tripped && RealtimePlant::now_ns() - st.last_write_ns > wd * 1000000LL) {
        st.tripped = true;
        plant.set_output(plant.input_min(a), a);
        show_output(a);
      }
      const std::int64_t nm = std::llround(plant.position_um(a) * 1000.0);
      const auto nm16 = static_cast<std::uint16_t>(std::clamp<std::int64_t>(nm, 0, 65535));
      ir[map::kIrPositionNm16] = hr[map::kHrPositionNm16] = nm16;
      put32(&ir[map::kIrPositionNm], nm);
      put32(&hr[map::kHrPositionNm], nm);
      put32(&ir[map::kIrSamples], static_cast<std::int64_t>(plant.samples() & 0xffffffffu));
      ir[map::kIrStatus] = static_cast<std::uint16_t>((st.tripped ? map::kStatusWatchdog : 0) |
                                                      (st.clamped ? map::kStatusClamped : 0));
    }
  }
  // After the reply: what the request wrote to an axis's output registers becomes its output.
  void after(const std::uint8_t* q) {
    const int fc = q[header_length];
    int addr = -1, count = 0;
    const auto u16 = [&](int i) { return (q[header_length + i] << 8) | q[header_length + i + 1]; };
    if (fc == 0x06) {
      addr = u16(1);
      count = 1;
    } else if (fc == 0x10) {
      addr = u16(1);
      count = u16(3);
    } else if (fc == 0x17) {
      addr = u16(5);
      count = u16(7);
    }
    if (addr < 0) return;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const int base = static_cast<int>(a) * map::kAxisBlock;
      const auto covers = [&](int r, int n) {
        return addr <= base + r && addr + count >= base + r + n;
      };
      double v = NAN;
      if (covers(map::kHrOutputMv, 2)) {
        v = get32(&holding(a)[map::kHrOutputMv]) / 1000.0;
      } else if (covers(map::kHrOutputCode, 1)) {
        v = plant.input_min(a) +
            holding(a)[map::kHrOutputCode] / 65535.0 * (plant.input_max(a) - plant.input_min(a));
      }
      if (std::isnan(v)) continue;
      AxisState& st = axes[a];
      st.last_write_ns = RealtimePlant::now_ns();
      st.tripped = false;
      st.clamped = v < plant.input_min(a) || v > plant.input_max(a);
      plant.set_output(v, a);
      show_output(a);
    }
  }
};

int serve_tcp(Server& s, const std::string& bind, int port) {
  modbus_t* ctx = modbus_new_tcp(bind.c_str(), port);
  if (ctx == nullptr) {
    std::cerr << "hystbench-simdaq: " << modbus_strerror(errno) << "\n";
    return 1;
  }
  const int listener = modbus_tcp_listen(ctx, 8);
  if (listener < 0) {
    std::cerr << "hystbench-simdaq: cannot listen on " << bind << ":" << port << ": "
              << modbus_strerror(errno) << "\n";
    return 1;
  }
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  getsockname(listener, reinterpret_cast<sockaddr*>(&addr), &len);
  s.header_length = modbus_get_header_length(ctx);
  std::cout << "hystbench-simdaq: listening on tcp " << bind << ":" << ntohs(addr.sin_port)
            << std::endl;
  std::set<int> clients;
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  for (;;) {
    fd_set fds;
    FD_ZERO(&fds);
    FD_SET(listener, &fds);
    int maxfd = listener;
    for (int c : clients) {
      FD_SET(c, &fds);
      maxfd = std::max(maxfd, c);
    }
    if (select(maxfd + 1, &fds, nullptr, nullptr, nullptr) < 0) {
      if (errno == EINTR) continue;
      std::perror("hystbench-simdaq: select");
      return 1;
    }
    if (FD_ISSET(listener, &fds)) {
      const int c = accept(listener, nullptr, nullptr);
      if (c >= 0) clients.insert(c);
    }
    for (auto it = clients.begin(); it != clients.end();) {
      const int c = *it;
      if (!FD_ISSET(c, &fds)) {
        ++it;
        continue;
      }
      modbus_set_socket(ctx, c);
      const int rc = modbus_receive(ctx, query);
      if (rc > 0) {
        s.before();
        modbus_reply(ctx, query, rc, s.regs);
        s.after(query);
        ++it;
      } else if (rc == -1) {
        close(c);
        it = clients.erase(it);
      } else {
        ++it;
      }
    }
  }
}

int serve_rtu(Server& s, const std::string& device, int baud, char parity, int stop_bits,
              int slave) {
  modbus_t* ctx = modbus_new_rtu(device.c_str(), baud, parity, 8, stop_bits);
  if (ctx == nullptr || modbus_set_slave(ctx, slave) != 0 || modbus_connect(ctx) != 0) {
    std::cerr << "hystbench-simdaq: cannot open " << device << ": " << modbus_strerror(errno)
              << "\n";
    return 1;
  }
  s.header_length = modbus_get_header_length(ctx);
  std::cout << "hystbench-simdaq: serving rtu " << device << " " << baud << " 8" << parity
            << stop_bits << " slave " << slave << std::endl;
  std::uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
  int errors = 0;
  for (;;) {
    const int rc = modbus_receive(ctx, query);
    if (rc > 0) {
      errors = 0;
      s.before();
      modbus_reply(ctx, query, rc, s.regs);
      s.after(query);
    } else if (rc == -1) {
      // A garbled frame: drop it. A line that keeps failing (the other end closed): give up.
      if (++errors > 1000) {
        std::cerr << "hystbench-simdaq: " << device << ": " << modbus_strerror(errno) << "\n";
        return 1;
      }
      modbus_flush(ctx);
      usleep(1000);
    }
  }
}

int run(int argc, char** argv) {
  CLI::App app{
      "hystbench-simdaq - Modbus TCP/RTU server wrapping the simulated piezo actuator\n"
      "Register map: docs/drivers.md. Prints the endpoint on stdout once it serves."};
  std::string bind = "127.0.0.1", rtu, parity = "none", actuator_file, stage_file;
  int port = 1502, baud = 115200, stop_bits = 1, slave = 1, watchdog_ms = 0;
  double sim_rate_hz = 10000.0;
  app.add_option("--bind", bind, "TCP address to listen on")->capture_default_str();
  app.add_option("--port", port, "TCP port (0: any free one, printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  app.add_option("--rtu", rtu, "Serve Modbus RTU on this serial device instead of TCP");
  app.add_option("--baud", baud, "RTU baud rate")->capture_default_str();
  app.add_option("--parity", parity, "RTU parity")
      ->check(CLI::IsMember({"none", "even", "odd"}))
      ->capture_default_str();
  app.add_option("--stop-bits", stop_bits, "RTU stop bits")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  app.add_option("--slave-id", slave, "RTU slave address")
      ->check(CLI::Range(1, 247))
      ->capture_default_str();
  app.add_option("--sim-rate-hz", sim_rate_hz, "Simulation sample rate")
      ->check(CLI::Range(100.0, 100000.0))
      ->capture_default_str();
  app.add_option("--watchdog-ms", watchdog_ms,
                 "Output to the input minimum when no output write came for this long (0: off; "
                 "holding register 3 changes it)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  auto* actuator =
      app.add_option("--actuator", actuator_file, "Simulated actuator config (JSON, sim format)")
          ->check(CLI::ExistingFile);
  app.add_option("--stage", stage_file,
                 "Simulate a stage of several axes instead: \"xy\" for the default XY stage (as "
                 "config/loopback-xy.toml), or a JSON file of the [driver.loopback.stage] table. "
                 "Axis i's registers sit at i * 16 in both tables ([driver.modbus] axes, "
                 "axis_stride = 16)")
      ->excludes(actuator);
  CLI11_PARSE(app, argc, argv);

  std::unique_ptr<RealtimePlant> plant;
  try {
    plant = hystbench::apps::make_plant(stage_file, actuator_file, sim_rate_hz);
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simdaq: " << (stage_file.empty() ? actuator_file : stage_file) << ": "
              << e.what() << "\n";
    return 2;
  }
  const auto blocks = static_cast<int>(plant->axes()) * map::kAxisBlock;
  modbus_mapping_t* regs = modbus_mapping_new(0, 0, blocks, blocks);
  Server s{*plant, regs};
  for (std::size_t a = 0; a < plant->axes(); ++a) {
    s.input(a)[map::kIrIdent] = map::kIdent;
    s.input(a)[map::kIrMapVersion] = 1;
    s.holding(a)[map::kHrWatchdogMs] = static_cast<std::uint16_t>(watchdog_ms);
    s.show_output(a);
  }
  s.input(0)[map::kIrAxes] = static_cast<std::uint16_t>(plant->axes());
  s.before();
  if (!rtu.empty()) {
    return serve_rtu(s, rtu, baud,
                     parity == "none"   ? 'N'
                     : parity == "even" ? 'E'
                                        : 'O',
                     stop_bits, slave);
  }
  return serve_tcp(s, bind, port);
}

}  // namespace

int main(int argc, char** argv) {
  return hystbench::common::run_main("hystbench-simdaq", run, argc, argv);
}
