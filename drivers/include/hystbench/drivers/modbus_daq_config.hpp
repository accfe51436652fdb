#pragma once
// Configuration of the Modbus DAQ driver: the [driver.modbus] table. Every key is optional;
// an unknown key, a wrong type or a value out of range is an error naming the key path.
//
//   transport = "tcp" | "rtu"                      (tcp)
//   host, port                                     TCP server  (127.0.0.1, 502)
//   device, baud, parity, data_bits, stop_bits     RTU line    (/dev/ttyUSB0, 115200, "none", 8, 1)
//   slave_id                                       [0, 255]    (1)
//   response_timeout_ms                            (0, 10000]  (20)
//   io = "thread" | "loop"                         where the transactions run (thread)
//       thread: an I/O thread (IoThreadDriver) exchanges the latest command and measurement
//               with the loop through a wait-free buffer; read() says kStale when nothing new
//               arrived this tick.
//       loop:   write()/read() do the transactions in the loop thread; the loop rate must fit.
//   write_read = false                             one function-23 transaction per tick
//                                                  (the measurement must be in holding registers)
//   max_rate_hz                                    (0, 20000]: the highest loop rate in io = "loop"
//                                                  (default: RTU from the line's wire time, TCP
//                                                  20000; activation measures and may refuse)
//   max_stale_reads                                [1, 1e9] stale reads in a row = fault
//                                                  (default: 20 ms of ticks, at least 10)
//   max_failed_transactions                        [1, 1e9] failed ones in a row = fault (3)
//   reconnect_interval_ms                          [1, 60000] between connection attempts (200)
//   safe_output_v                                  the output on fault and when idle (output.min_v)
//   axes = ["x", "y"]                              a stage of several axes: their names (1 to 6,
//                                                  a-z 0-9 _), in the order of their register
//                                                  blocks. Axis i's output and measurement are at
//                                                  the addresses below plus i * axis_stride, with
//                                                  the same encoding and scaling. (one axis)
//   axis_stride                                    [1, 65535] registers from one axis's block to
//                                                  the next (16: hystbench-simdaq --stage)
//   [output]       table = "holding", address, format ("u16" | "s16" | "u32" | "s32"),
//                  word_order ("big" | "little"), scale [V/count], offset [V], min_v, max_v
//   [measurement]  table ("input" | "holding"), address, format, word_order,
//                  scale [µm/count], offset [µm]
// Not real-time: parse_modbus_daq_config() allocates and throws std::invalid_argument.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hystbench/drivers/modbus_registers.hpp"

namespace hystbench::drivers {

struct ModbusDaqConfig {
  enum class Transport : std::uint8_t { kTcp, kRtu };
  enum class IoMode : std::uint8_t { kThread, kLoop };

  Transport transport = Transport::kTcp;
  std::string host = "127.0.0.1";
  int port = 502;
  std::string device = "/dev/ttyUSB0";
  int baud = 115200;
  char parity = 'N';  ///< 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  int slave_id = 1;
  double response_timeout_ms = 20.0;
  IoMode io = IoMode::kThread;
  bool write_read = false;
  double max_rate_hz = 0.0;           ///< 0 = derived (see above)
  std::uint64_t max_stale_reads = 0;  ///< 0 = 20 ms of loop ticks, at least 10
  std::uint64_t max_failed_transactions = 3;
  double reconnect_interval_ms = 200.0;
  double safe_output_v = 0.0;
  std::vector<std::string> axes;  ///< names of a stage's axes; empty = one axis
  int axis_stride = 16;           ///< registers between axis blocks
  double output_min_v = 0.0;
  double output_max_v = 150.0;
  /// Default: holding register 0, u16, 0..150 V over 0..65535.
  RegisterChannel output{RegisterTable::kHolding, 0,  RegisterFormat::kU16, WordOrder::kHighFirst,
                         150.0 / 65535.0,         0.0};
  /// Default: input register 0, u16, 1 nm per count.
  RegisterChannel measurement{RegisterTable::kInput, 0,     RegisterFormat::kU16,
                              WordOrder::kHighFirst, 0.001, 0.0};

  /// Axes served: axes.size(), at least 1.
  std::size_t axis_count() const noexcept { return axes.empty() ? 1 : axes.size(); }
  /// The register offset of axis `i`'s block: i * axis_stride.
  int axis_offset(std::size_t i) const noexcept { return static_cast<int>(i) * axis_stride; }
  /// "tcp 127.0.0.1:502" or "rtu /dev/ttyUSB0 115200 8N1", for messages.
  std::string endpoint() const;
  /// Modbus transactions per tick: per axis 1 with write_read, else 2.
  int transactions_per_tick() const noexcept {
    return static_cast<int>(axis_count()) * (write_read ? 1 : 2);
  }
  /// Shortest time the serial line needs for one tick's frames [s] (0 for TCP).
  double rtu_wire_time_s() const noexcept;
};

/// Parses the [driver.modbus] table (null = all defaults). Throws std::invalid_argument whose
/// message starts with the key path ("driver.modbus.output.format: ...").
ModbusDaqConfig parse_modbus_daq_config(const nlohmann::json& params);

}  // namespace hystbench::drivers
