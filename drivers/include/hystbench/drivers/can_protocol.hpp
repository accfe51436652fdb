#pragma once
// The frame protocol between the bench and a CAN piezo amplifier, shared by the driver and
// hystbench-simamp. Four frames, each configured in its own table:
//   [setpoint]  bench -> amplifier, every tick: the output as a scaled integer field
//   [feedback]  amplifier -> bench: the position as a scaled integer field, optional status byte
//   [enable]    bench -> amplifier at activation: fixed data bytes
//   [disable]   bench -> amplifier at deactivation and on error: fixed data bytes
// Frame keys: id (11-bit, or 29-bit with extended = true), length (data bytes, 1..8).
// Field keys (setpoint, feedback): start_byte, bytes (1, 2 or 4), signed, byte_order
// ("little" | "big"), scale [unit per count], offset [unit at count 0]:
//   value = offset + scale * count  (V for the setpoint, µm for the feedback).
// Feedback only: status_byte (-1 = none) and fault_mask: status & fault_mask != 0 = amplifier
// fault. encode/decode are real-time safe; parse_can_protocol() allocates and throws.
#include <linux/can.h>

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hystbench::drivers {

struct CanFrameId {
  std::uint32_t id = 0;
  bool extended = false;
  /// The can_id of a frame with this id (EFF flag when extended).
  canid_t can_id() const noexcept { return extended ? (id | CAN_EFF_FLAG) : id; }
  bool matches(const can_frame& f) const noexcept {
    return (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG | CAN_EFF_MASK)) == can_id();
  }
  std::string describe() const;  ///< "0x180" or "0x12345678 (extended)"
};

struct CanField {
  int start_byte = 0;
  int bytes = 4;  ///< 1, 2 or 4
  bool is_signed = true;
  bool big_endian = false;
  double scale = 0.001;
  double offset = 0.0;
  std::int64_t count_min() const noexcept;
  std::int64_t count_max() const noexcept;
  /// Writes the count of `value` (rounded, clamped) into data; returns the count.
  std::int64_t encode(double value, std::uint8_t* data) const noexcept;
  double decode(const std::uint8_t* data) const noexcept;
};

struct CanProtocol {
  CanFrameId setpoint_id{0x200, false};
  int setpoint_length = 4;
  CanField setpoint{0, 4, true, false, 0.001, 0.0};  ///< millivolts
  CanFrameId feedback_id{0x180, false};
  int feedback_length = 5;
  CanField feedback{0, 4, true, false, 0.001, 0.0};  ///< nanometres
  int status_byte = 4;                               ///< -1 = none
  std::uint8_t fault_mask = 0x01;
  CanFrameId enable_id{0x100, false};
  std::vector<std::uint8_t> enable_data{1};
  CanFrameId disable_id{0x100, false};
  std::vector<std::uint8_t> disable_data{0};

  enum class Decoded : std::uint8_t { kOther, kFeedback, kMalformed };

  can_frame setpoint_frame(double volts) const noexcept;
  can_frame feedback_frame(double position_um, std::uint8_t status) const noexcept;
  can_frame enable_frame() const noexcept;
  can_frame disable_frame() const noexcept;
  /// Classifies `f`; for kFeedback sets position [µm] and status (0 without a status byte).
  Decoded decode_feedback(const can_frame& f, double& position_um,
                          std::uint8_t& status) const noexcept;
  /// 1 enable, 0 disable, -1 neither (for the amplifier side).
  int enable_command(const can_frame& f) const noexcept;
  /// The setpoint [V] of a setpoint frame, false for any other (for the amplifier side).
  bool decode_setpoint(const can_frame& f, double& volts) const noexcept;
  /// The same frames for the node `offset` ids further on: each of the four ids plus `offset`
  /// (a stage's axis i at i * node_step). The caller keeps the ids in range
  /// (check_can_nodes()).
  CanProtocol at_node(std::uint32_t offset) const;
};

/// Checks that `nodes` copies of `protocol`, `node_step` ids apart, keep every id within its
/// 11 or 29 bits and no setpoint id on any node's feedback id; throws std::invalid_argument at
/// `path` ("driver.can.node_step: ...") naming the ids.
void check_can_nodes(const CanProtocol& protocol, std::size_t nodes, std::uint32_t node_step,
                     const std::string& path);

/// Longest time a frame of `data_bytes` needs on the bus, bit stuffing included, in bits.
int can_frame_bits(int data_bytes, bool extended) noexcept;

/// Parses the frame tables (setpoint, feedback, enable, disable) of `table` at `path`
/// ("driver.can"); other keys are ignored here. Throws std::invalid_argument naming the key.
CanProtocol parse_can_protocol(const nlohmann::json& table, const std::string& path);

}  // namespace hystbench::drivers
