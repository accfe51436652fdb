// hystbench-simamp: a CAN piezo amplifier simulator. The simulated actuator behind the frame
// protocol of the CAN amplifier driver (can_protocol.hpp; defaults as config/can.toml), on a
// SocketCAN interface (vcan0, can0) or on an inherited socket carrying struct can_frame.
// Each setpoint frame is answered with a feedback frame; the plant advances with the wall clock.
// Status byte of the feedback: bit 0 fault, bit 1 enabled, bit 2 heartbeat tripped.
// Fault injection for tests and demos: --stop-feedback-after, --malformed-after,
// --bus-off-after (an error frame with CAN_ERR_BUSOFF), --fault-after (the status fault bit).
#include <linux/can/error.h>
#include <poll.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>

#include "hystbench/drivers/can_bus.hpp"
#include "hystbench/drivers/can_protocol.hpp"
#include "realtime_plant.hpp"
#include "run_main.hpp"

namespace hd = hystbench::drivers;
using hystbench::apps::RealtimePlant;

namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "hystbench-simamp - CAN piezo amplifier simulator (the simulated actuator behind the CAN\n"
      "amplifier driver's frame protocol). See docs/drivers.md for candump/cansend usage."};
  std::string interface, protocol_file, actuator_file;
  int fd = -1;
  double sim_rate_hz = 10000.0;
  int heartbeat_ms = 100;
  std::uint64_t stop_after = 0, malformed_after = 0, bus_off_after = 0, fault_after = 0;
  auto* src = app.add_option_group("bus");
  src->add_option("--interface", interface, "SocketCAN interface (vcan0, can0)");
  src->add_option("--fd", fd, "An inherited socket carrying struct can_frame");
  src->require_option(1);
  app.add_option("--protocol", protocol_file,
                 "Frame protocol as JSON (the [driver.can] table; frames only)")
      ->check(CLI::ExistingFile);
  app.add_option("--actuator", actuator_file, "Simulated actuator config (JSON, sim format)")
      ->check(CLI::ExistingFile);
  app.add_option("--sim-rate-hz", sim_rate_hz, "Simulation sample rate")
      ->check(CLI::Range(100.0, 100000.0))
      ->capture_default_str();
  app.add_option("--heartbeat-ms", heartbeat_ms,
                 "No setpoint for this long: output to the input minimum, disabled (0: off)")
      ->capture_default_str();
  app.add_option("--stop-feedback-after", stop_after, "Answer only this many setpoints");
  app.add_option("--malformed-after", malformed_after,
                 "After this many setpoints answer with a feedback frame one byte short");
  app.add_option("--bus-off-after", bus_off_after,
                 "After this many setpoints send a bus-off error frame and go silent");
  app.add_option("--fault-after", fault_after, "After this many setpoints set the fault bit");
  CLI11_PARSE(app, argc, argv);

  hd::CanProtocol protocol;
  hystbench::sim::SimulatedActuatorConfig cfg;
  try {
    if (!protocol_file.empty()) {
      std::ifstream in(protocol_file);
      protocol = hd::parse_can_protocol(nlohmann::json::parse(in), "protocol");
    }
    if (!actuator_file.empty()) {
      std::ifstream in(actuator_file);
      cfg = hystbench::sim::from_json(nlohmann::json::parse(in));
    }
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simamp: " << e.what() << "\n";
    return 2;
  }
  std::unique_ptr<hd::CanSocket> sock;
  try {
    sock = fd >= 0 ? std::make_unique<hd::CanSocket>(fd) : hd::open_socketcan(interface);
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simamp: " << e.what() << "\n";
    return 1;
  }
  RealtimePlant plant(cfg, sim_rate_hz);
  std::cout << "hystbench-simamp: ready on "
            << (fd >= 0 ? "fd " + std::to_string(fd) : "interface " + interface) << ": setpoint "
            << protocol.setpoint_id.describe() << ", feedback " << protocol.feedback_id.describe()
            << ", enable " << protocol.enable_id.describe() << std::endl;

  bool enabled = false, tripped = false, silent = false;
  std::uint64_t setpoints = 0;
  std::int64_t last_setpoint_ns = RealtimePlant::now_ns();
  for (;;) {
    pollfd p{sock->fd(), POLLIN, 0};
    ::poll(&p, 1, 1);
    if (heartbeat_ms > 0 && enabled &&
        RealtimePlant::now_ns() - last_setpoint_ns > heartbeat_ms * 1000000LL) {
      plant.advance();
      plant.set_output(plant.input_min());
      enabled = false;
      tripped = true;
    }
    can_frame f{};
    int rc = 0;
    while ((rc = sock->receive(f)) == 1) {
      if (const int en = protocol.enable_command(f); en >= 0) {
        plant.advance();
        enabled = en == 1;
        tripped = false;
        if (!enabled) plant.set_output(plant.input_min());
        last_setpoint_ns = RealtimePlant::now_ns();
        continue;
      }
      double v = 0.0;
      if (!protocol.decode_setpoint(f, v)) continue;
      ++setpoints;
      last_setpoint_ns = RealtimePlant::now_ns();
      plant.advance();
      if (enabled) plant.set_output(v);
      if (silent || (stop_after > 0 && setpoints > stop_after)) continue;
      if (bus_off_after > 0 && setpoints > bus_off_after) {
        can_frame err{};
        err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
        err.can_dlc = CAN_ERR_DLC;
        sock->send(err);
        silent = true;
        continue;
      }
      const std::uint8_t status =
          static_cast<std::uint8_t>((fault_after > 0 && setpoints > fault_after ? 0x1 : 0) |
                                    (enabled ? 0x2 : 0) | (tripped ? 0x4 : 0));
      can_frame fb = protocol.feedback_frame(plant.position_um(), status);
      if (malformed_after > 0 && setpoints > malformed_after) fb.can_dlc -= 1;
      sock->send(fb);
    }
    if (rc < 0) {
      if (errno == 0) return 0;  // the other end closed
      std::cerr << "hystbench-simamp: " << std::strerror(errno) << "\n";
      return 1;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  return hystbench::apps::run_main("hystbench-simamp", run, argc, argv);
}
