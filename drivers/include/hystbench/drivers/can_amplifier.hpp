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
//   axes = ["x", "y"]             a stage of several axes, a node each: axis i's four frames
//                                 are the ones above with i * node_step added to each id (one)
//   node_step = 1                 [1, 0x1000000] ids from one axis's node to the next
// activate() refuses a down, stopped or bus-off interface, a loop rate the bitrate cannot
// carry, and an amplifier that does not answer the enable frame and a setpoint with feedback
// within max(heartbeat_timeout_ms, 200 ms); every message names the interface and the cause.
// A stage: write_axes() sends every axis's setpoint, read_axes() is fresh once every axis's
// feedback has come since the last fresh one (each axis's newest); activation enables and waits
// for every axis, naming the one that does not answer; the heartbeat watches each axis.
// Faults (read() returns kFault): feedback silent beyond the heartbeat timeout, a malformed
// feedback frame (wrong length), bus-off (error frame), the amplifier's fault bit, the socket
// closed, 3 failed sends in a row. describe_fault() says which, in words.
// Real-time: write()/read()/safe_state() make non-blocking socket calls only.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/drivers/can_bus.hpp"
#include "hystbench/drivers/can_protocol.hpp"
#include "hystbench/drivers/driver.hpp"

namespace hystbench::drivers {

class CanAmplifierDriver final : public DriverInterface {
 public:
  enum class Fault : int { kNone = 0, kHeartbeat, kMalformed, kBusOff, kAmplifier, kSocket, kSend };

  CanAmplifierDriver();
  /// Uses `controller` instead of libsocketcan on the interface (tests).
  explicit CanAmplifierDriver(std::unique_ptr<CanController> controller);
  ~CanAmplifierDriver() override;

  Result on_configure(const nlohmann::json& params, double rate_hz) override;
  /// Checks the controller, enables the amplifier and waits for its first feedback frame.
  Result on_activate() override;
  /// The safe setpoint and the disable frame, then the socket closes.
  Result on_deactivate() override;

  /// Sends the setpoint frame (non-blocking).
  DriverStatus write(double output_v) noexcept override;
  /// Takes every frame that arrived (at most 64, non-blocking); fresh when one was feedback.
  DriverStatus read(Measurement& out) noexcept override;
  /// Every axis's setpoint frame, in axis order.
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept override;
  /// As read(), fresh once each of the first out.size() axes has answered since the last
  /// fresh read.
  DriverStatus read_axes(std::span<Measurement> out) noexcept override;
  /// The safe setpoint on every axis.
  DriverStatus safe_state() noexcept override;
  std::size_t axes() const noexcept override { return nodes_.size(); }

  /// max_rate_hz from max_rate_hz and, after activation, the bitrate; measurement_resolution_um
  /// = |feedback.scale| (one count of the position field).
  DriverInfo info() const noexcept override;
  double activation_position_um() const noexcept override { return activation_y_; }
  std::string_view type() const noexcept override { return "can"; }
  nlohmann::json diagnostics() const override;
  std::string describe_fault(int cause, std::int64_t detail) const override;

  const CanProtocol& protocol() const noexcept { return protocol_; }

 private:
  void supervise() noexcept;
  void stop_supervisor() noexcept;
  /// Safe setpoint and disable frame, socket closed; returns the failure `message`.
  Result release(const std::string& message);
  // on_activate's steps, in order; `where` names the interface or socket in their messages.
  /// The interface is up and its controller (when there is one) neither bus-off, after a
  /// restart where configured, nor stopped; reads its bitrate (0 without a controller).
  Result check_controller(const std::string& where);
  /// The loop rate fits on the bus: a setpoint and a feedback frame per axis and tick at the
  /// bitrate.
  Result check_bus_rate(const std::string& where);
  /// The socket: a duplicate of socket_fd, else the interface's.
  Result open_socket();
  /// Sends every axis's enable frame, then safe setpoints until each axis's feedback answers
  /// without a fault; keeps the first axis's position as the activation position.
  Result enable_amplifier(const std::string& where);
  /// "axis y: " on a stage, "" on one axis (for messages).
  std::string axis_words(std::size_t a) const;
  /// Sends every axis's setpoint at `volts`; false when one send failed.
  bool send_setpoints(double volts) noexcept;

  CanProtocol protocol_;
  std::vector<CanProtocol> nodes_{CanProtocol{}};  ///< per axis: protocol_ at its node
  std::vector<std::string> axis_names_;            ///< empty: one axis
  std::uint32_t node_step_ = 1;
  std::string interface_;
  int socket_fd_ = -1;
  std::int64_t heartbeat_ns_ = 50'000'000;
  bool restart_on_bus_off_ = false;
  double declared_max_rate_hz_ = 0.0;
  double max_rate_hz_ = 20000.0;
  double rate_hz_ = 0.0;
  double safe_output_v_ = 0.0, output_min_v_ = 0.0, output_max_v_ = 150.0;

  std::unique_ptr<CanController> controller_;
  bool injected_controller_ = false;
  std::unique_ptr<CanSocket> socket_;
  std::uint32_t bitrate_ = 0;
  std::string controller_state_ = "unknown";
  double activation_y_ = 0.0;

  // Loop-thread state.
  int consecutive_send_failures_ = 0;
  std::array<double, kMaxAxes> newest_um_{};  ///< each axis's newest feedback
  std::uint32_t answered_ = 0;                ///< bit a: axis a answered since the last fresh

  // Shared with diagnostics() and the supervisor.
  std::array<std::atomic<std::int64_t>, kMaxAxes> last_feedback_ns_{};
  std::atomic<int> silent_axis_{0};  ///< the axis of the last heartbeat fault
  std::atomic<bool> bus_off_{false};
  std::atomic<bool> socket_dead_{false};
  std::atomic<std::uint64_t> sent_{0}, received_{0}, feedback_{0}, malformed_{0}, bus_offs_{0};
  std::atomic<std::uint64_t> send_failures_{0}, restarts_{0};
  std::atomic<bool> quit_{false};
  std::thread supervisor_;
};

}  // namespace hystbench::drivers
