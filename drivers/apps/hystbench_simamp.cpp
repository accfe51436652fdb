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
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "hystbench/common/run_main.hpp"
#include "hystbench/drivers/can_bus.hpp"
#include "hystbench/drivers/can_protocol.hpp"
#include "realtime_plant.hpp"

namespace hd = hystbench::drivers;
using hystbench::apps::RealtimePlant;

namespace {

// The command line: the bus, the protocol and actuator files, the simulation and the faults.
struct SimampOptions {
  std::string interface, protocol_file, actuator_file;
  int fd = -1;
  double sim_rate_hz = 10000.0;
  int heartbeat_ms = 100;
  std::uint64_t stop_after = 0, malformed_after = 0, bus_off_after = 0, fault_after = 0;
};

void add_simamp_options(CLI::App& app, SimampOptions& o) {
  auto* src = app.add_option_group("bus");
  src->add_option("--interface", o.interface, "SocketCAN interface (vcan0, can0)");
  src->add_option("--fd", o.fd, "An inherited socket carrying struct can_frame");
  src->require_option(1);
  app.add_option("--protocol", o.protocol_file,
                 "Frame protocol as JSON (the [driver.can] table; frames only)")
      ->check(CLI::ExistingFile);
  app.add_option("--actuator", o.actuator_file, "Simulated actuator config (JSON, sim format)")
      ->check(CLI::ExistingFile);
  app.add_option("--sim-rate-hz", o.sim_rate_hz, "Simulation sample rate")
      ->check(CLI::Range(100.0, 100000.0))
      ->capture_default_str();
  app.add_option("--heartbeat-ms", o.heartbeat_ms,
                 "No setpoint for this long: output to the input minimum, disabled (0: off)")
      ->capture_default_str();
  app.add_option("--stop-feedback-after", o.stop_after, "Answer only this many setpoints");
  app.add_option("--malformed-after", o.malformed_after,
                 "After this many setpoints answer with a feedback frame one byte short");
  app.add_option("--bus-off-after", o.bus_off_after,
                 "After this many setpoints send a bus-off error frame and go silent");
  app.add_option("--fault-after", o.fault_after, "After this many setpoints set the fault bit");
}

// The protocol and the actuator from their files (the defaults without them); false after
// printing why a file cannot be read.
bool load_simamp_files(const SimampOptions& o, hd::CanProtocol& protocol,
                       hystbench::sim::SimulatedActuatorConfig& cfg) {
  try {
    if (!o.protocol_file.empty()) {
      std::ifstream in(o.protocol_file);
      protocol = hd::parse_can_protocol(nlohmann::json::parse(in), "protocol");
    }
    if (!o.actuator_file.empty()) {
      std::ifstream in(o.actuator_file);
      cfg = hystbench::sim::from_json(nlohmann::json::parse(in));
    }
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simamp: " << e.what() << "\n";
    return false;
  }
  return true;
}

// The amplifier behind the socket: the plant, the enable and heartbeat state, the setpoints
// counted for the fault injection.
class Amplifier {
 public:
  Amplifier(const SimampOptions& o, const hd::CanProtocol& protocol, hd::CanSocket& sock,
            RealtimePlant& plant)
      : o_(o), protocol_(protocol), sock_(sock), plant_(plant) {}

  // Answers frames until the other end closes (0) or the socket fails (1).
  int serve() {
    for (;;) {
      pollfd p{sock_.fd(), POLLIN, 0};
      ::poll(&p, 1, 1);
      check_heartbeat();
      can_frame f{};
      int rc = 0;
      while ((rc = sock_.receive(f)) == 1) on_frame(f);
      if (rc < 0) {
        if (errno == 0) return 0;  // the other end closed
        std::cerr << "hystbench-simamp: " << std::strerror(errno) << "\n";
        return 1;
      }
    }
  }

 private:
  // No setpoint for --heartbeat-ms while enabled: output to the input minimum, disabled.
  void check_heartbeat() {
    if (o_.heartbeat_ms > 0 && enabled_ &&
        RealtimePlant::now_ns() - last_setpoint_ns_ > o_.heartbeat_ms * 1000000LL) {
      plant_.advance();
      plant_.set_output(plant_.input_min());
      enabled_ = false;
      tripped_ = true;
    }
  }

  void on_frame(const can_frame& f) {
    if (const int en = protocol_.enable_command(f); en >= 0) {
      plant_.advance();
      enabled_ = en == 1;
      tripped_ = false;
      if (!enabled_) plant_.set_output(plant_.input_min());
      last_setpoint_ns_ = RealtimePlant::now_ns();
      return;
    }
    double v = 0.0;
    if (!protocol_.decode_setpoint(f, v)) return;
    ++setpoints_;
    last_setpoint_ns_ = RealtimePlant::now_ns();
    plant_.advance();
    if (enabled_) plant_.set_output(v);
    answer_setpoint();
  }

  // The feedback to a setpoint, or what the fault injection sends instead (nothing, a bus-off
  // error frame, a frame one byte short, the fault bit).
  void answer_setpoint() {
    if (silent_ || (o_.stop_after > 0 && setpoints_ > o_.stop_after)) return;
    if (o_.bus_off_after > 0 && setpoints_ > o_.bus_off_after) {
      can_frame err{};
      err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
      err.can_dlc = CAN_ERR_DLC;
      sock_.send(err);
      silent_ = true;
      return;
    }
    const std::uint8_t status =
        static_cast<std::uint8_t>((o_.fault_after > 0 && setpoints_ > o_.fault_after ? 0x1 : 0) |
                                  (enabled_ ? 0x2 : 0) | (tripped_ ? 0x4 : 0));
    can_frame fb = protocol_.feedback_frame(plant_.position_um(), status);
    if (o_.malformed_after > 0 && setpoints_ > o_.malformed_after) fb.can_dlc -= 1;
    sock_.send(fb);
  }

  const SimampOptions& o_;
  const hd::CanProtocol& protocol_;
  hd::CanSocket& sock_;
  RealtimePlant& plant_;
  bool enabled_ = false, tripped_ = false, silent_ = false;
  std::uint64_t setpoints_ = 0;
  std::int64_t last_setpoint_ns_ = RealtimePlant::now_ns();
};

int run(int argc, char** argv) {
  CLI::App app{
      "hystbench-simamp - CAN piezo amplifier simulator (the simulated actuator behind the CAN\n"
      "amplifier driver's frame protocol). See docs/drivers.md for candump/cansend usage."};
  SimampOptions o;
  add_simamp_options(app, o);
  CLI11_PARSE(app, argc, argv);

  hd::CanProtocol protocol;
  hystbench::sim::SimulatedActuatorConfig cfg;
  if (!load_simamp_files(o, protocol, cfg)) return 2;
  std::unique_ptr<hd::CanSocket> sock;
  try {
    sock = o.fd >= 0 ? std::make_unique<hd::CanSocket>(o.fd) : hd::open_socketcan(o.interface);
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simamp: " << e.what() << "\n";
    return 1;
  }
  RealtimePlant plant(cfg, o.sim_rate_hz);
  std::cout << "hystbench-simamp: ready on "
            << (o.fd >= 0 ? "fd " + std::to_string(o.fd) : "interface " + o.interface)
            << ": setpoint " << protocol.setpoint_id.describe() << ", feedback "
            << protocol.feedback_id.describe() << ", enable " << protocol.enable_id.describe()
            << std::endl;
  return Amplifier(o, protocol, *sock, plant).serve();
}

}  // namespace

int main(int argc, char** argv) {
  return hystbench::common::run_main("hystbench-simamp", run, argc, argv);
}
