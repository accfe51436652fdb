#include "hystbench/drivers/can_amplifier.hpp"

#include <fcntl.h>
#include <linux/can/error.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "details/clock.hpp"
#include "details/json_params.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::drivers {

using compensation::fixed;
using details::monotonic_ns;
using details::ParamError;
using details::Params;

namespace {
constexpr int kMaxFramesPerRead = 64;
constexpr int kMaxSendFailures = 3;
}  // namespace

CanAmplifierDriver::CanAmplifierDriver() = default;

CanAmplifierDriver::CanAmplifierDriver(std::unique_ptr<CanController> controller)
    : controller_(std::move(controller)), injected_controller_(controller_ != nullptr) {}

CanAmplifierDriver::~CanAmplifierDriver() { stop_supervisor(); }

Result CanAmplifierDriver::on_configure(const nlohmann::json& params, double rate_hz) {
  try {
    const Params p(params, "driver.can");
    p.allow_only({"interface", "socket_fd", "heartbeat_timeout_ms", "restart_on_bus_off",
                  "max_rate_hz", "safe_output_v", "output_min_v", "output_max_v", "setpoint",
                  "feedback", "enable", "disable", "axes", "node_step"});
    interface_ = p.string("interface", "");
    socket_fd_ = static_cast<int>(p.integer("socket_fd", -1, 0, 1 << 20));
    if (interface_.empty() && socket_fd_ < 0) {
      throw ParamError("driver.can.interface: required (the SocketCAN interface, e.g. \"can0\")");
    }
    heartbeat_ns_ =
        static_cast<std::int64_t>(p.number("heartbeat_timeout_ms", 50.0, 0.0, 10000.0) * 1e6);
    if (heartbeat_ns_ <= 0) throw ParamError("driver.can.heartbeat_timeout_ms: must be > 0");
    restart_on_bus_off_ = p.boolean("restart_on_bus_off", false);
    declared_max_rate_hz_ = p.number("max_rate_hz", 0.0, 0.0, 20000.0);
    output_min_v_ = p.number("output_min_v", 0.0, -1e6, 1e6);
    output_max_v_ = p.number("output_max_v", 150.0, -1e6, 1e6);
    if (!(output_max_v_ > output_min_v_)) {
      throw ParamError("driver.can.output_max_v: must be greater than output_min_v");
    }
    safe_output_v_ = p.number("safe_output_v", output_min_v_, output_min_v_, output_max_v_);
    protocol_ = parse_can_protocol(params, "driver.can");
    axis_names_ = p.axis_names("axes");
    if (p.has("node_step") && !p.has("axes")) {
      throw ParamError("driver.can.node_step: only with axes (a stage of several axes)");
    }
    node_step_ = static_cast<std::uint32_t>(p.integer("node_step", 1, 1, 0x1000000));
    const std::size_t n = std::max<std::size_t>(1, axis_names_.size());
    check_can_nodes(protocol_, n, node_step_, "driver.can");
    nodes_.clear();
    for (std::size_t a = 0; a < n; ++a) {
      nodes_.push_back(protocol_.at_node(static_cast<std::uint32_t>(a) * node_step_));
    }
  } catch (const ParamError& e) {
    return Result::failure(e.what());
  } catch (const std::invalid_argument& e) {
    return Result::failure(e.what());
  }
  max_rate_hz_ = declared_max_rate_hz_ > 0.0 ? declared_max_rate_hz_ : 20000.0;
  if (rate_hz > max_rate_hz_) {
    return Result::failure("loop.rate_hz: " + fixed(rate_hz, 0) +
                           " Hz is beyond driver.can.max_rate_hz = " + fixed(max_rate_hz_, 0));
  }
  rate_hz_ = rate_hz;
  if (!injected_controller_) {
    controller_ = interface_.empty() ? nullptr : make_libsocketcan_controller(interface_);
  }
  return Result::success();
}

Result CanAmplifierDriver::on_activate() {
  const std::string where = interface_.empty() ? "socket " + std::to_string(socket_fd_)
                                               : "interface '" + interface_ + "'";
  if (auto r = check_controller(where); !r) return r;
  if (auto r = check_bus_rate(where); !r) return r;
  if (auto r = open_socket(); !r) return r;
  if (auto r = enable_amplifier(where); !r) return r;
  consecutive_send_failures_ = 0;
  answered_ = 0;
  for (auto& t : last_feedback_ns_) t = monotonic_ns();
  bus_off_ = false;
  socket_dead_ = false;
  if (restart_on_bus_off_ && controller_) {
    quit_ = false;
    supervisor_ = std::thread([this] { supervise(); });
  }
  return Result::success();
}

Result CanAmplifierDriver::check_controller(const std::string& where) {
  try {
    if (socket_fd_ < 0 && !interface_is_up(interface_)) {
      return Result::failure("driver.can: " + where + " is down (ip link set " + interface_ +
                             " up type can bitrate 1000000)");
    }
  } catch (const std::exception& e) {
    return Result::failure(e.what());
  }
  bitrate_ = 0;
  if (!controller_) return Result::success();
  CanController::State s = controller_->state();
  if (s == CanController::State::kBusOff && restart_on_bus_off_) {
    if (auto r = controller_->restart(); !r) return r;
    restarts_.fetch_add(1);
    s = controller_->state();
  }
  controller_state_ = to_string(s);
  if (s == CanController::State::kBusOff) {
    return Result::failure("driver.can: " + where + " is bus-off: restart it (ip link set " +
                           interface_ +
                           " type can restart) or set driver.can.restart_on_bus_off = true");
  }
  if (s == CanController::State::kStopped || s == CanController::State::kSleeping) {
    return Result::failure("driver.can: " + where + " controller is " + controller_state_ +
                           " (ip link set " + interface_ + " up type can bitrate 1000000)");
  }
  bitrate_ = controller_->bitrate();
  return Result::success();
}

Result CanAmplifierDriver::check_bus_rate(const std::string& where) {
  if (bitrate_ == 0) return Result::success();
  const int bits = static_cast<int>(axes()) *
                   (can_frame_bits(protocol_.setpoint_length, protocol_.setpoint_id.extended) +
                    can_frame_bits(protocol_.feedback_length, protocol_.feedback_id.extended));
  const double bus_max = std::floor(static_cast<double>(bitrate_) / bits);
  max_rate_hz_ = declared_max_rate_hz_ > 0.0 ? std::min(declared_max_rate_hz_, bus_max) : bus_max;
  if (rate_hz_ > max_rate_hz_) {
    return Result::failure("loop.rate_hz: " + fixed(rate_hz_, 0) + " Hz is beyond what " + where +
                           " carries at " + std::to_string(bitrate_) + " bit/s: a setpoint and " +
                           "a feedback frame" + (axes() > 1 ? " per axis" : "") + " take up to " +
                           std::to_string(bits) + " bits, so at most " + fixed(bus_max, 0) + " Hz");
  }
  return Result::success();
}

Result CanAmplifierDriver::open_socket() {
  try {
    if (socket_fd_ >= 0) {
      const int fd = ::fcntl(socket_fd_, F_DUPFD_CLOEXEC, 0);
      if (fd < 0) {
        return Result::failure("driver.can.socket_fd: " + std::to_string(socket_fd_) +
                               " is not open: " + std::strerror(errno));
      }
      socket_ = std::make_unique<CanSocket>(fd);
    } else {
      socket_ = open_socketcan(interface_);
    }
  } catch (const std::exception& e) {
    return Result::failure(e.what());
  }
  return Result::success();
}

std::string CanAmplifierDriver::axis_words(std::size_t a) const {
  return axis_names_.empty() ? "" : "axis " + axis_names_[a] + ": ";
}

bool CanAmplifierDriver::send_setpoints(double volts) noexcept {
  bool ok = true;
  for (const CanProtocol& node : nodes_) ok = socket_->send(node.setpoint_frame(volts)) && ok;
  return ok;
}

Result CanAmplifierDriver::enable_amplifier(const std::string& where) {
  can_frame f{};
  while (socket_->receive(f) == 1) {
  }
  // Enable every axis, then setpoints at the safe output until each one answers.
  for (std::size_t a = 0; a < nodes_.size(); ++a) {
    if (!socket_->send(nodes_[a].enable_frame())) {
      return release(("driver.can: " + axis_words(a) + "cannot send the enable frame " +
                      nodes_[a].enable_id.describe() + " on " + where + ": " +
                      std::strerror(errno)));
    }
  }
  const std::int64_t wait_ns = std::max<std::int64_t>(heartbeat_ns_, 200'000'000);
  const std::int64_t until = monotonic_ns() + wait_ns;
  std::vector<bool> answered(nodes_.size(), false);
  std::vector<std::uint8_t> status(nodes_.size(), 0);
  const auto all = [&] {
    return std::find(answered.begin(), answered.end(), false) == answered.end();
  };
  while (!all() && monotonic_ns() < until) {
    send_setpoints(safe_output_v_);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    int rc = 0;
    while ((rc = socket_->receive(f)) == 1) {
      for (std::size_t a = 0; a < nodes_.size(); ++a) {
        double y = 0.0;
        std::uint8_t st = 0;
        if (nodes_[a].decode_feedback(f, y, st) != CanProtocol::Decoded::kFeedback) continue;
        if (a == 0) activation_y_ = y;
        answered[a] = true;
        status[a] = st;
      }
    }
    if (rc < 0) {
      return release(("driver.can: " + where + " failed while waiting for feedback: " +
                      (errno == 0 ? "the peer closed the socket" : std::strerror(errno))));
    }
  }
  for (std::size_t a = 0; a < nodes_.size(); ++a) {
    if (!answered[a]) {
      return release((
          "driver.can: " + axis_words(a) + "no feedback frame " + nodes_[a].feedback_id.describe() +
          " on " + where + " within " + fixed(wait_ns / 1e6, 0) + " ms of the enable frame " +
          nodes_[a].enable_id.describe() + ": is the amplifier powered and on the bus?"));
    }
    if ((status[a] & protocol_.fault_mask) != 0) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "%02X", status[a]);
      return release("driver.can: " + axis_words(a) + "the amplifier reports a fault (status 0x" +
                     hex + ") on " + where);
    }
  }
  return Result::success();
}

Result CanAmplifierDriver::release(const std::string& message) {
  if (socket_) {
    send_setpoints(safe_output_v_);
    for (const CanProtocol& node : nodes_) socket_->send(node.disable_frame());
  }
  socket_.reset();
  return Result::failure(message);
}

void CanAmplifierDriver::supervise() noexcept {
  while (!quit_.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (!bus_off_.load()) continue;
    // Not real-time: netlink through libsocketcan, then enable the amplifier again.
    try {
      if (controller_->restart()) {
        restarts_.fetch_add(1);
        for (auto& t : last_feedback_ns_) t.store(monotonic_ns());
        bus_off_.store(false);
        if (socket_) {
          for (const CanProtocol& node : nodes_) socket_->send(node.enable_frame());
        }
      }
    } catch (...) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

void CanAmplifierDriver::stop_supervisor() noexcept {
  quit_ = true;
  if (supervisor_.joinable()) supervisor_.join();
}

Result CanAmplifierDriver::on_deactivate() {
  stop_supervisor();
  bool ok = send_setpoints(safe_output_v_);
  for (const CanProtocol& node : nodes_) ok = socket_->send(node.disable_frame()) && ok;
  const int err = errno;
  socket_.reset();
  if (!ok) {
    return Result::failure("driver.can: the safe setpoint or the disable frame was not sent: " +
                           std::string(std::strerror(err)));
  }
  return Result::success();
}

DriverStatus CanAmplifierDriver::write(double output_v) noexcept {
  return write_axes(std::span<const double>(&output_v, 1));
}

DriverStatus CanAmplifierDriver::write_axes(std::span<const double> outputs_v) noexcept {
  if (socket_dead_.load(std::memory_order_relaxed) || bus_off_.load(std::memory_order_relaxed)) {
    return DriverStatus::kFault;
  }
  std::size_t n = 0, sent = 0;
  for (; n < outputs_v.size() && n < nodes_.size(); ++n) {
    sent += socket_->send(nodes_[n].setpoint_frame(outputs_v[n])) ? 1 : 0;
  }
  sent_.fetch_add(sent, std::memory_order_relaxed);
  if (sent == n) {
    consecutive_send_failures_ = 0;
    return DriverStatus::kOk;
  }
  send_failures_.fetch_add(1, std::memory_order_relaxed);
  if (++consecutive_send_failures_ >= kMaxSendFailures) {
    report_fault(Fault::kSend, errno);
    return DriverStatus::kFault;
  }
  return DriverStatus::kOk;
}

DriverStatus CanAmplifierDriver::read(Measurement& out) noexcept {
  return read_axes(std::span<Measurement>(&out, 1));
}

DriverStatus CanAmplifierDriver::read_axes(std::span<Measurement> out) noexcept {
  bool malformed = false, amp_fault = false;
  std::int64_t detail = 0;
  const std::int64_t now = monotonic_ns();
  can_frame f{};
  for (int i = 0; i < kMaxFramesPerRead && !socket_dead_.load(std::memory_order_relaxed); ++i) {
    const int rc = socket_->receive(f);
    if (rc == 0) break;
    if (rc < 0) {
      socket_dead_.store(true, std::memory_order_relaxed);
      report_fault(Fault::kSocket, errno);
      break;
    }
    received_.fetch_add(1, std::memory_order_relaxed);
    if ((f.can_id & CAN_ERR_FLAG) != 0) {
      if ((f.can_id & CAN_ERR_BUSOFF) != 0) {
        bus_off_.store(true, std::memory_order_relaxed);
        bus_offs_.fetch_add(1, std::memory_order_relaxed);
        report_fault(Fault::kBusOff);
      } else if ((f.can_id & CAN_ERR_RESTARTED) != 0) {
        bus_off_.store(false, std::memory_order_relaxed);
      }
      continue;
    }
    for (std::size_t a = 0; a < nodes_.size(); ++a) {
      double y = 0.0;
      std::uint8_t status = 0;
      const CanProtocol::Decoded d = nodes_[a].decode_feedback(f, y, status);
      if (d == CanProtocol::Decoded::kOther) continue;
      if (d == CanProtocol::Decoded::kMalformed) {
        malformed_.fetch_add(1, std::memory_order_relaxed);
        malformed = true;
        detail = f.can_dlc;
      } else if ((status & protocol_.fault_mask) != 0) {
        feedback_.fetch_add(1, std::memory_order_relaxed);
        amp_fault = true;
        detail = status;
      } else {
        feedback_.fetch_add(1, std::memory_order_relaxed);
        newest_um_[a] = y;
        answered_ |= 1u << a;
        last_feedback_ns_[a].store(now, std::memory_order_relaxed);
      }
      break;
    }
  }
  if (socket_dead_.load(std::memory_order_relaxed) || bus_off_.load(std::memory_order_relaxed)) {
    return DriverStatus::kFault;
  }
  if (malformed) {
    report_fault(Fault::kMalformed, detail);
    return DriverStatus::kFault;
  }
  if (amp_fault) {
    report_fault(Fault::kAmplifier, detail);
    return DriverStatus::kFault;
  }
  for (std::size_t a = 0; a < nodes_.size(); ++a) {
    const std::int64_t silent = now - last_feedback_ns_[a].load(std::memory_order_relaxed);
    if (silent > heartbeat_ns_) {
      silent_axis_.store(static_cast<int>(a), std::memory_order_relaxed);
      report_fault(Fault::kHeartbeat, silent);
      return DriverStatus::kFault;
    }
  }
  // Fresh once every axis asked for has answered since the last fresh read. A feedback frame
  // read in the tick of a setpoint answers an earlier one: the amplifier cannot sample and send
  // within the microseconds between write() and read().
  const std::size_t n = std::min(out.size(), nodes_.size());
  const std::uint32_t wanted = (1u << n) - 1u;
  if ((answered_ & wanted) != wanted) return DriverStatus::kStale;
  answered_ = 0;
  for (std::size_t a = 0; a < n; ++a) {
    out[a].position_um = newest_um_[a];
    out[a].response_ticks = 1;
  }
  return DriverStatus::kOk;
}

DriverStatus CanAmplifierDriver::safe_state() noexcept {
  if (socket_dead_.load(std::memory_order_relaxed)) return DriverStatus::kFault;
  // Sent even when bus-off: the frame waits in the queue for the restart.
  return send_setpoints(safe_output_v_) ? DriverStatus::kOk : DriverStatus::kError;
}

DriverInfo CanAmplifierDriver::info() const noexcept {
  DriverInfo i;
  i.max_rate_hz = max_rate_hz_;
  i.output_min_v = output_min_v_;
  i.output_max_v = output_max_v_;
  i.safe_output_v = safe_output_v_;
  i.measurement_resolution_um = std::abs(protocol_.feedback.scale);
  return i;
}

std::string CanAmplifierDriver::describe_fault(int cause, std::int64_t detail) const {
  switch (static_cast<Fault>(cause)) {
    case Fault::kNone:
      break;
    case Fault::kHeartbeat: {
      const auto a = static_cast<std::size_t>(silent_axis_.load(std::memory_order_relaxed));
      return axis_words(std::min(a, nodes_.size() - 1)) + "no feedback frame " +
             nodes_[std::min(a, nodes_.size() - 1)].feedback_id.describe() + " for " +
             fixed(detail / 1e6, 1) +
             " ms (heartbeat_timeout_ms = " + fixed(heartbeat_ns_ / 1e6, 1) + ")";
    }
    case Fault::kMalformed:
      return "malformed feedback frame " + protocol_.feedback_id.describe() + ": " +
             std::to_string(detail) + " data bytes, expected " +
             std::to_string(protocol_.feedback_length);
    case Fault::kBusOff:
      return "bus-off (error frame)" + std::string(restart_on_bus_off_ && controller_
                                                       ? ": restarting the controller"
                                                       : ": restart the interface");
    case Fault::kAmplifier:
      return "the amplifier reports a fault: status byte " + std::to_string(detail) +
             " & fault_mask " + std::to_string(protocol_.fault_mask);
    case Fault::kSocket:
      return std::string("the CAN socket failed: ") +
             (detail == 0 ? "the peer closed it" : std::strerror(static_cast<int>(detail)));
    case Fault::kSend:
      return std::to_string(kMaxSendFailures) +
             " setpoint frames in a row not sent: " + std::strerror(static_cast<int>(detail));
  }
  return DriverInterface::describe_fault(cause, detail);
}

nlohmann::json CanAmplifierDriver::diagnostics() const {
  nlohmann::json d = {{"type", "can"},
                      {"interface", interface_},
                      {"controller_state", controller_state_},
                      {"bitrate", bitrate_},
                      {"bus_off", bus_off_.load()},
                      {"frames_sent", sent_.load()},
                      {"frames_received", received_.load()},
                      {"feedback_frames", feedback_.load()},
                      {"malformed_frames", malformed_.load()},
                      {"bus_offs", bus_offs_.load()},
                      {"restarts", restarts_.load()},
                      {"send_failures", send_failures_.load()}};
  // A stage's nodes.
  if (!axis_names_.empty()) {
    d["axis_names"] = axis_names_;
    d["node_step"] = node_step_;
  }
  return d;
}

}  // namespace hystbench::drivers
