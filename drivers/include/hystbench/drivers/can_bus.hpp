#pragma once
// The two things the CAN amplifier driver needs from the bus, each behind a small interface so
// tests can own them:
//   CanSocket      a datagram socket carrying one `struct can_frame` per message: a SocketCAN
//                  raw socket (open_socketcan) or any socket a test or bridge hands over
//                  (a socketpair). send()/receive() never block and never allocate.
//   CanController  the controller's state, bitrate and restart (libsocketcan over netlink);
//                  not real-time.
#include <linux/can.h>

#include <cstdint>
#include <memory>
#include <string>

#include "hystbench/drivers/driver.hpp"

namespace hystbench::drivers {

class CanSocket {
 public:
  /// Takes ownership of `fd` and makes it non-blocking.
  explicit CanSocket(int fd) noexcept;
  ~CanSocket();
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;

  /// True when the frame was queued; false with errno (EAGAIN/ENOBUFS: queue full).
  bool send(const can_frame& f) noexcept;
  /// 1 a frame was read, 0 none pending, -1 error or the peer closed (errno; 0 for closed).
  int receive(can_frame& f) noexcept;
  int fd() const noexcept { return fd_; }

 private:
  int fd_ = -1;
};

/// A raw CAN socket bound to `interface`, receiving bus-off and controller error frames.
/// Throws std::runtime_error naming the interface and the cause.
std::unique_ptr<CanSocket> open_socketcan(const std::string& interface);

/// Whether `interface` exists and is administratively up (SIOCGIFFLAGS). Throws when the
/// interface does not exist.
bool interface_is_up(const std::string& interface);

class CanController {
 public:
  enum class State {
    kErrorActive,
    kErrorWarning,
    kErrorPassive,
    kBusOff,
    kStopped,
    kSleeping,
    kUnknown
  };
  virtual ~CanController() = default;
  /// The controller state; kUnknown for interfaces without one (vcan).
  virtual State state() = 0;
  /// The bitrate [bit/s]; 0 when not known (vcan).
  virtual std::uint32_t bitrate() = 0;
  /// Restarts the controller after bus-off.
  virtual Result restart() = 0;
};

const char* to_string(CanController::State s) noexcept;

/// libsocketcan on `interface`.
std::unique_ptr<CanController> make_libsocketcan_controller(const std::string& interface);

}  // namespace hystbench::drivers
