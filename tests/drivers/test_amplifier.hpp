#pragma once
// The CAN amplifier's end of a socketpair carrying struct can_frame, answered from a thread (the
// tests play the amplifier with it), and a fake controller (state, bitrate, restart).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "hystbench/drivers/can_bus.hpp"
#include "hystbench/drivers/can_protocol.hpp"

namespace hystbench::test {

/// The amplifier's end of the socketpair, answered from a thread: `nodes` amplifier nodes (a
/// stage's axes), node i at the default ids plus i, each answering 0.3 um per V.
class TestAmplifier {
 public:
  enum class Mode { kAnswer, kSilent, kMalformed, kFaultBit };
  explicit TestAmplifier(int nodes = 1) : nodes_(nodes) {
    int sv[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv), 0);
    driver_fd = sv[0];
    amp_fd_ = sv[1];
    thread_ = std::thread([this] { run(); });
  }
  ~TestAmplifier() {
    quit_ = true;
    thread_.join();
    ::close(amp_fd_);
    ::close(driver_fd);
  }
  void set_mode(Mode m) { mode_ = m; }
  /// Node i stops answering (-1: every node answers).
  void set_silent_node(int i) { silent_node_ = i; }
  /// Answer only one setpoint in `n` (a slow amplifier; 1 = every one).
  void set_answer_every(int n) { answer_every_ = n; }
  void send(const can_frame& f) { ::send(amp_fd_, &f, sizeof f, MSG_NOSIGNAL); }
  std::vector<can_frame> frames() {
    std::lock_guard lock(m_);
    return frames_;
  }
  int driver_fd = -1;

 private:
  void run() {
    const drivers::CanProtocol defaults;
    std::vector<drivers::CanProtocol> nodes;
    for (int i = 0; i < nodes_; ++i) nodes.push_back(defaults.at_node(i));
    while (!quit_) {
      can_frame f{};
      const ssize_t n = ::recv(amp_fd_, &f, sizeof f, MSG_DONTWAIT);
      if (n != sizeof f) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        continue;
      }
      {
        std::lock_guard lock(m_);
        frames_.push_back(f);
      }
      double v = 0.0;
      int node = 0;
      while (node < nodes_ && !nodes[node].decode_setpoint(f, v)) ++node;
      if (node == nodes_) continue;
      can_frame fb = nodes[node].feedback_frame(0.3 * v, mode_ == Mode::kFaultBit ? 0x1 : 0x2);
      if (node == silent_node_) continue;
      if (mode_ == Mode::kSilent || ++setpoints_ % answer_every_ != 0) continue;
      if (mode_ == Mode::kMalformed) fb.can_dlc = 3;
      send(fb);
    }
  }
  int amp_fd_ = -1;
  const int nodes_;
  std::atomic<int> silent_node_{-1};
  std::atomic<bool> quit_{false};
  std::atomic<Mode> mode_{Mode::kAnswer};
  std::atomic<int> answer_every_{1};
  int setpoints_ = 0;
  std::mutex m_;
  std::vector<can_frame> frames_;
  std::thread thread_;
};

struct FakeControllerState {
  drivers::CanController::State state = drivers::CanController::State::kErrorActive;
  std::uint32_t bitrate = 1000000;
  std::atomic<int> restarts{0};
};

class FakeController : public drivers::CanController {
 public:
  explicit FakeController(std::shared_ptr<FakeControllerState> s) : s_(std::move(s)) {}
  State state() override { return s_->state; }
  std::uint32_t bitrate() override { return s_->bitrate; }
  drivers::Result restart() override {
    ++s_->restarts;
    s_->state = State::kErrorActive;
    return drivers::Result::success();
  }

 private:
  std::shared_ptr<FakeControllerState> s_;
};

}  // namespace hystbench::test
