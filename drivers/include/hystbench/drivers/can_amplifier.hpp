#pragma once
// CAN piezo amplifier driver (SocketCAN raw socket, libsocketcan for the controller).
// Per tick: write() sends the setpoint frame, read() takes every frame that arrived (never
// blocks) and returns the newest position from the feedback frames, kStale (age_ticks) when
// none came this tick. A fresh position has response_ticks 1: it answers an earlier setpoint.
//
// Config [driver.can] (unknown keys are errors naming them):
//   interface = "can0"            the SocketCAN interface (state, bitrate and restart through
//                                 libsocketcan at activation)
//   socket_fd = N                 instead of a raw socket: an open socket carrying one
//                                 struct can_frame per message (tests, user-space bridges);
//                                 interface is then optional (no controller checks without)
//   heartbeat_timeout_ms = 50     (0, 10000]: no valid feedback frame for this long = fault
//   restart_on_bus_off = false    restart the controller (can_do_restart) after bus-off
//   max_rate_hz                   (0, 20000]; default: from the bitrate at activation (both
//                                 frames must fit in a tick), 20000 without a bitrate
//   safe_output_v, output_min_v, output_max_v   [V] (0, 0, 150)
//   [setpoint] [feedback] [enable] [disable]    the frames: see can_protocol.hpp
// activate() refuses a down, stopped or bus-off interface, a loop rate the bitrate cannot
// carry, and an amplifier that does not answer the enable frame and a setpoint with feedback
// within max(heartbeat_timeout_ms, 200 ms); every message names the interface and the cause.
// Faults (read() returns kFault): feedback silent beyond the heartbeat timeout, a malformed
// feedback frame (wrong length), bus-off (error frame), the amplifier's fault bit, the socket
// closed, 3 failed sends in a row. diagnostics()["last_fault"] says which, in words.
// Real-time: write()/read()/safe_state() make non-blocking socket calls only.
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include "hystbench/drivers/can_bus.hpp"
#include "hystbench/drivers/can_protocol.hpp"
#include "hystbench/drivers/driver.hpp"

namespace hystbench::drivers {

class CanAmplifierDriver final : public Driver {
 public:
  CanAmplifierDriver();
  /// Uses `controller` instead of libsocketcan on the interface (tests).
  explicit CanAmplifierDriver(std::unique_ptr<CanController> controller);
  ~CanAmplifierDriver() override;

  Result configure(const nlohmann::json& params, double rate_hz) override;
  Result activate() override;
  Result deactivate() override;
  Result on_error() override;

  DriverStatus write(double output_v) noexcept override;
  DriverStatus read(Measurement& out) noexcept override;
  DriverStatus safe_state() noexcept override;

  double max_rate_hz() const noexcept override { return max_rate_hz_; }
  double output_min_v() const noexcept override { return output_min_v_; }
  double output_max_v() const noexcept override { return output_max_v_; }
  double safe_output_v() const noexcept override { return safe_output_v_; }
  /// |feedback.scale|: one count of the position field.
  double measurement_resolution_um() const noexcept override {
    return protocol_.feedback.scale < 0 ? -protocol_.feedback.scale : protocol_.feedback.scale;
  }
  std::string_view type() const noexcept override { return "can"; }
  nlohmann::json diagnostics() const override;

  const CanProtocol& protocol() const noexcept { return protocol_; }

  enum class Fault : int { kNone = 0, kHeartbeat, kMalformed, kBusOff, kAmplifier, kSocket, kSend };

 private:
  void fault(Fault cause, std::int64_t detail) noexcept;
  void supervise() noexcept;
  void stop_supervisor() noexcept;
  /// Safe setpoint and disable frame, socket closed; returns the failure `message`.
  Result release(const std::string& message);

  CanProtocol protocol_;
  std::string interface_;
  int socket_fd_ = -1;
  std::int64_t heartbeat_ns_ = 50'000'000;
  bool restart_on_bus_off_ = false;
  double declared_max_rate_hz_ = 0.0;
  double max_rate_hz_ = 20000.0;
  double rate_hz_ = 0.0;
  double safe_output_v_ = 0.0, output_min_v_ = 0.0, output_max_v_ = 150.0;
  bool configured_ = false;

  std::unique_ptr<CanController> controller_;
  bool injected_controller_ = false;
  std::unique_ptr<CanSocket> socket_;
  std::atomic<bool> active_{false};
  std::uint32_t bitrate_ = 0;
  std::string controller_state_ = "unknown";

  // Loop-thread state.
  double last_y_ = 0.0;
  std::uint64_t age_ = 0;
  int consecutive_send_failures_ = 0;

  // Shared with diagnostics() and the supervisor.
  std::atomic<std::int64_t> last_feedback_ns_{0};
  std::atomic<bool> bus_off_{false};
  std::atomic<bool> socket_dead_{false};
  std::atomic<double> output_v_{0.0};
  std::atomic<double> position_um_{0.0};
  std::atomic<std::uint64_t> sent_{0}, received_{0}, feedback_{0}, malformed_{0}, bus_offs_{0};
  std::atomic<std::uint64_t> send_failures_{0}, stale_reads_{0}, restarts_{0};
  std::atomic<int> last_fault_{0};
  std::atomic<std::int64_t> last_fault_detail_{0};
  std::atomic<bool> quit_{false};
  std::thread supervisor_;
};

}  // namespace hystbench::drivers
