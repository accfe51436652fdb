#pragma once
// One libmodbus connection (TCP or RTU) and the per-tick exchange of the Modbus DAQ driver:
// write the output registers and read the measurement registers, with function 23 or with a
// write (6 or 16) and a read (3 or 4). Not thread-safe: one thread at a time.
// exchange() blocks for at most about two response timeouts; it does not allocate.
#include <modbus/modbus.h>

#include <cstdint>
#include <string>

#include "details/clock.hpp"
#include "hystbench/drivers/modbus_daq_config.hpp"

namespace hystbench::drivers::details {

class ModbusLink {
 public:
  /// What failed last (for messages).
  enum class Op : std::uint8_t { kNone, kConnect, kWrite, kRead, kWriteRead };

  /// Creates the libmodbus context; throws std::runtime_error naming the cause.
  explicit ModbusLink(const ModbusDaqConfig& config);
  ~ModbusLink();
  ModbusLink(const ModbusLink&) = delete;
  ModbusLink& operator=(const ModbusLink&) = delete;

  /// Opens the connection (TCP connect or serial port). False with last_errno() set.
  bool connect() noexcept;
  void close() noexcept;
  bool connected() const noexcept { return connected_; }

  /// Writes `out` (output.registers() words) when `write`, then reads the measurement into
  /// `in` (measurement.registers() words) when `read`, both at their addresses plus `offset`
  /// (an axis's block: config.axis_offset(i)); one function-23 transaction when the config
  /// says write_read and both are asked for. Each Modbus transaction's round-trip time
  /// goes to `rtt_ns[i]` (up to 2). Returns the number of transactions done, or -1 on failure
  /// (last_errno(), last_op() say why; a broken link is closed).
  int exchange(const std::uint16_t* out, std::uint16_t* in, bool write, bool read,
               std::int64_t* rtt_ns, int offset = 0) noexcept;

  int last_errno() const noexcept { return last_errno_; }
  Op last_op() const noexcept { return last_op_; }
  /// "reading input register 0: Illegal data address" and the like; `offset` as exchange()'s
  /// (the registers named are the axis's, with its name).
  static std::string describe(Op op, int err, const ModbusDaqConfig& config, int offset = 0);

 private:
  void fail(Op op) noexcept;
  const ModbusDaqConfig& config_;
  modbus_t* ctx_ = nullptr;
  bool connected_ = false;
  int last_errno_ = 0;
  Op last_op_ = Op::kNone;
};

}  // namespace hystbench::drivers::details
