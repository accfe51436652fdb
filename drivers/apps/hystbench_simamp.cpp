// hystbench-simamp: a CAN piezo amplifier simulator. The simulated actuator behind the frame
// protocol of the CAN amplifier driver (can_protocol.hpp; defaults as config/can.toml), on a
// SocketCAN interface (vcan0, can0) or on an inherited socket carrying struct can_frame.
// Each setpoint frame is answered with a feedback frame; the plant advances with the wall clock.
// --stage: a simulated stage of several axes, one amplifier node per axis (ids + i * node step).
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
#include <stdexcept>
#include <string>
#include <vector>

#include "hystbench/common/run_main.hpp"
#include "hystbench/drivers/can_bus.hpp"
#include "hystbench/drivers/can_protocol.hpp"
#include "realtime_plant.hpp"

namespace hd = hystbench::drivers;
using hystbench::apps::RealtimePlant;

namespace {

// The command line: the bus, the protocol and actuator files, the simulation and the faults.
struct SimampOptions {
  std::string interface, protocol_file, actuator_file, stage_file;
  int fd = -1;
  std::uint32_t node_step = 1;
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
  auto* actuator =
      app.add_option("--actuator", o.actuator_file, "Simulated actuator config (JSON, sim format)")
          ->check(CLI::ExistingFile);
  app.add_option("--stage", o.stage_file,
                 "Simulate a stage of several axes instead, one amplifier node per axis: \"xy\" "
                 "for the default XY stage (as config/loopback-xy.toml), or a JSON file of the "
                 "[driver.loopback.stage] table. Axis i's frames are the protocol's ids plus i * "
                 "--node-step ([driver.can] axes, node_step)")
      ->excludes(actuator);
  app.add_option("--node-step", o.node_step, "Ids from one axis's node to the next (--stage)")
      ->check(CLI::Range(1, 0x1000000))
      ->capture_default_str();
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

// The protocol and the plant from their files (the defaults without them); false after
// printing why a file cannot be read.
bool load_simamp_files(const SimampOptions& o, hd::CanProtocol& protocol,
                       std::unique_ptr<RealtimePlant>& plant) {
  try {
    if (!o.protocol_file.empty()) {
      std::ifstream in(o.protocol_file);
      protocol = hd::parse_can_protocol(nlohmann::json::parse(in), "protocol");
    }
    try {
      plant = hystbench::apps::make_plant(o.stage_file, o.actuator_file, o.sim_rate_hz);
    } catch (const std::exception& e) {
      throw std::runtime_error((o.stage_file.empty() ? o.actuator_file : o.stage_file) + ": " +
                               e.what());
    }
    hd::check_can_nodes(protocol, plant->axes(), o.node_step, "--node-step");
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simamp: " << e.what() << "\n";
    return false;
  }
  return true;
}

// The amplifier behind the socket, a node per axis: the plant, each axis's enable and
// heartbeat state, the setpoints counted for the fault injection.
class Amplifier {
 public:
  Amplifier(const SimampOptions& o, const hd::CanProtocol& protocol, hd::CanSocket& sock,
            RealtimePlant& plant)
      : o_(o), sock_(sock), plant_(plant), axes_(plant.axes()) {
    for (std::size_t a = 0; a < plant.axes(); ++a) {
      nodes_.push_back(protocol.at_node(static_cast<std::uint32_t>(a) * o.node_step));
    }
  }

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
  struct AxisState {
    bool enabled = false, tripped = false;
    std::int64_t last_setpoint_ns = RealtimePlant::now_ns();
  };

  // No setpoint for --heartbeat-ms while enabled: that axis's output to its input minimum,
  // disabled.
  void check_heartbeat() {
    for (std::size_t a = 0; a < axes_.size(); ++a) {
      AxisState& st = axes_[a];
      if (o_.heartbeat_ms > 0 && st.enabled &&
          RealtimePlant::now_ns() - st.last_setpoint_ns > o_.heartbeat_ms * 1000000LL) {
        plant_.advance();
        plant_.set_output(plant_.input_min(a), a);
        st.enabled = false;
        st.tripped = true;
      }
    }
  }

  void on_frame(const can_frame& f) {
    for (std::size_t a = 0; a < nodes_.size(); ++a) {
      AxisState& st = axes_[a];
      if (const int en = nodes_[a].enable_command(f); en >= 0) {
        plant_.advance();
        st.enabled = en == 1;
        st.tripped = false;
        if (!st.enabled) plant_.set_output(plant_.input_min(a), a);
        st.last_setpoint_ns = RealtimePlant::now_ns();
        return;
      }
      double v = 0.0;
      if (!nodes_[a].decode_setpoint(f, v)) continue;
      ++setpoints_;
      st.last_setpoint_ns = RealtimePlant::now_ns();
      plant_.advance();
      if (st.enabled) plant_.set_output(v, a);
      answer_setpoint(a);
      return;
    }
  }

  // The feedback to axis a's setpoint, or what the fault injection sends instead (nothing, a
  // bus-off error frame, a frame one byte short, the fault bit).
  void answer_setpoint(std::size_t a) {
    if (silent_ || (o_.stop_after > 0 && setpoints_ > o_.stop_after)) return;
    if (o_.bus_off_after > 0 && setpoints_ > o_.bus_off_after) {
      can_frame err{};
      err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
      err.can_dlc = CAN_ERR_DLC;
      sock_.send(err);
      silent_ = true;
      return;
    }
    const AxisState& st = axes_[a];
    const std::uint8_t status =
        static_cast<std::uint8_t>((o_.fault_after > 0 && setpoints_ > o_.fault_after ? 0x1 : 0) |
                                  (st.enabled ? 0x2 : 0) | (st.tripped ? 0x4 : 0));
    can_frame fb = nodes_[a].feedback_frame(plant_.position_um(a), status);
    if (o_.malformed_after > 0 && setpoints_ > o_.malformed_after) fb.can_dlc -= 1;
    sock_.send(fb);
  }

  const SimampOptions& o_;
  std::vector<hd::CanProtocol> nodes_;
  hd::CanSocket& sock_;
  RealtimePlant& plant_;
  std::vector<AxisState> axes_;
  bool silent_ = false;
  std::uint64_t setpoints_ = 0;
};

int run(int argc, char** argv) {
  CLI::App app{
      "hystbench-simamp - CAN piezo amplifier simulator (the simulated actuator behind the CAN\n"
      "amplifier driver's frame protocol). See docs/drivers.md for candump/cansend usage."};
  SimampOptions o;
  add_simamp_options(app, o);
  CLI11_PARSE(app, argc, argv);

  hd::CanProtocol protocol;
  std::unique_ptr<RealtimePlant> plant;
  if (!load_simamp_files(o, protocol, plant)) return 2;
  std::unique_ptr<hd::CanSocket> sock;
  try {
    sock = o.fd >= 0 ? std::make_unique<hd::CanSocket>(o.fd) : hd::open_socketcan(o.interface);
  } catch (const std::exception& e) {
    std::cerr << "hystbench-simamp: " << e.what() << "\n";
    return 1;
  }
  std::cout << "hystbench-simamp: ready on "
            << (o.fd >= 0 ? "fd " + std::to_string(o.fd) : "interface " + o.interface)
            << ": setpoint " << protocol.setpoint_id.describe() << ", feedback "
            << protocol.feedback_id.describe() << ", enable " << protocol.enable_id.describe();
  if (plant->axes() > 1) {
    std::cout << "; " << plant->axes() << " axes, node step " << o.node_step;
  }
  std::cout << std::endl;
  return Amplifier(o, protocol, *sock, *plant).serve();
}

}  // namespace

int main(int argc, char** argv) {
  return hystbench::common::run_main("hystbench-simamp", run, argc, argv);
}
