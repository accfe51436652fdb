#include "hystbench/drivers/can_bus.hpp"

#include <fcntl.h>
#include <libsocketcan.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iterator>
#include <stdexcept>

namespace hystbench::drivers {

CanSocket::CanSocket(int fd) noexcept : fd_(fd) {
  const int flags = fcntl(fd_, F_GETFL);
  if (flags >= 0) fcntl(fd_, F_SETFL, flags | O_NONBLOCK);
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

bool CanSocket::send(const can_frame& f) noexcept {
  return ::send(fd_, &f, sizeof f, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof f);
}

int CanSocket::receive(can_frame& f) noexcept {
  const ssize_t n = ::recv(fd_, &f, sizeof f, MSG_DONTWAIT);
  if (n == static_cast<ssize_t>(sizeof f)) return 1;
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return 0;
  if (n == 0) errno = 0;  // the peer closed
  if (n > 0) errno = EMSGSIZE;
  return -1;
}

std::unique_ptr<CanSocket> open_socketcan(const std::string& interface) {
  if (interface.size() >= IFNAMSIZ) {
    throw std::runtime_error("driver.can.interface: '" + interface + "' is too long");
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    throw std::runtime_error(
        "driver.can: cannot open a raw CAN socket: " + std::string(std::strerror(errno)) +
        (errno == EAFNOSUPPORT ? " (this kernel has no SocketCAN)" : ""));
  }
  auto sock = std::make_unique<CanSocket>(fd);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
    throw std::runtime_error("driver.can.interface: no CAN interface '" + interface +
                             "': " + std::strerror(errno));
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  const can_err_mask_t errors = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED;
  ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    throw std::runtime_error("driver.can: cannot bind to '" + interface +
                             "': " + std::strerror(errno));
  }
  return sock;
}

bool interface_is_up(const std::string& interface) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  const int rc = ::ioctl(fd, SIOCGIFFLAGS, &ifr);
  const int err = errno;
  ::close(fd);
  if (rc < 0) {
    throw std::runtime_error("driver.can.interface: no interface '" + interface +
                             "': " + std::strerror(err));
  }
  return (ifr.ifr_flags & IFF_UP) != 0;
}

const char* to_string(CanController::State s) noexcept {
  // In CanController::State order.
  constexpr const char* kNames[] = {"error-active", "error-warning", "error-passive", "bus-off",
                                    "stopped",      "sleeping",      "unknown"};
  const auto i = static_cast<std::size_t>(s);
  return i < std::size(kNames) ? kNames[i] : "unknown";
}

namespace {

class LibsocketcanController final : public CanController {
 public:
  explicit LibsocketcanController(std::string interface) : interface_(std::move(interface)) {}
  State state() override {
    int s = 0;
    if (can_get_state(interface_.c_str(), &s) != 0) return State::kUnknown;
    switch (s) {
      case CAN_STATE_ERROR_ACTIVE:
        return State::kErrorActive;
      case CAN_STATE_ERROR_WARNING:
        return State::kErrorWarning;
      case CAN_STATE_ERROR_PASSIVE:
        return State::kErrorPassive;
      case CAN_STATE_BUS_OFF:
        return State::kBusOff;
      case CAN_STATE_STOPPED:
        return State::kStopped;
      case CAN_STATE_SLEEPING:
        return State::kSleeping;
      default:
        return State::kUnknown;
    }
  }
  std::uint32_t bitrate() override {
    can_bittiming bt{};
    if (can_get_bittiming(interface_.c_str(), &bt) != 0) return 0;
    return bt.bitrate;
  }
  Result restart() override {
    if (can_do_restart(interface_.c_str()) != 0) {
      return Result::failure("driver.can: restarting '" + interface_ +
                             "' failed (can_do_restart; needs CAP_NET_ADMIN and a bus-off "
                             "controller with restart-ms 0)");
    }
    return Result::success();
  }

 private:
  std::string interface_;
};

}  // namespace

std::unique_ptr<CanController> make_libsocketcan_controller(const std::string& interface) {
  return std::make_unique<LibsocketcanController>(interface);
}

}  // namespace hystbench::drivers
