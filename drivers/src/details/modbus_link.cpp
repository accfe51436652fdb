#include "details/modbus_link.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace hystbench::drivers::details {

ModbusLink::ModbusLink(const ModbusDaqConfig& config) : config_(config) {
  if (config.transport == ModbusDaqConfig::Transport::kTcp) {
    const std::string port = std::to_string(config.port);
    ctx_ = modbus_new_tcp_pi(config.host.c_str(), port.c_str());
  } else {
    ctx_ = modbus_new_rtu(config.device.c_str(), config.baud, config.parity, config.data_bits,
                          config.stop_bits);
  }
  if (ctx_ == nullptr) {
    throw std::runtime_error("driver.modbus: cannot create the libmodbus context for " +
                             config.endpoint() + ": " + modbus_strerror(errno));
  }
  if (modbus_set_slave(ctx_, config.slave_id) != 0) {
    const std::string why = modbus_strerror(errno);
    modbus_free(ctx_);
    ctx_ = nullptr;
    throw std::runtime_error("driver.modbus.slave_id: " + std::to_string(config.slave_id) +
                             " refused by libmodbus: " + why);
  }
  const auto us = static_cast<std::uint64_t>(config.response_timeout_ms * 1000.0);
  modbus_set_response_timeout(ctx_, static_cast<std::uint32_t>(us / 1000000),
                              static_cast<std::uint32_t>(us % 1000000));
  modbus_set_error_recovery(ctx_, MODBUS_ERROR_RECOVERY_NONE);
}

ModbusLink::~ModbusLink() {
  close();
  if (ctx_ != nullptr) modbus_free(ctx_);
}

bool ModbusLink::connect() noexcept {
  close();
  if (modbus_connect(ctx_) != 0) {
    fail(Op::kConnect);
    return false;
  }
  connected_ = true;
  return true;
}

void ModbusLink::close() noexcept {
  if (connected_) modbus_close(ctx_);
  connected_ = false;
}

void ModbusLink::fail(Op op) noexcept {
  last_errno_ = errno;
  last_op_ = op;
  if (op == Op::kConnect) return;
  const int e = last_errno_;
  const bool device_said_no = e >= EMBXILFUN && e <= EMBXGTAR;  // an exception reply
  if (device_said_no) return;
  if (config_.transport == ModbusDaqConfig::Transport::kRtu &&
      (e == ETIMEDOUT || e == EMBBADCRC || e == EMBBADDATA || e == EMBBADSLAVE || e == EMBMDATA ||
       e == EMBUNKEXC || e == EMBBADEXC)) {
    // A serial line has no connection to lose: drop what is in flight and go on.
    modbus_flush(ctx_);
    return;
  }
  // TCP: a late or garbled answer would be taken for the next one's; start over.
  close();
}

int ModbusLink::exchange(const std::uint16_t* out, std::uint16_t* in, bool write, bool read,
                         std::int64_t* rtt_ns, int offset) noexcept {
  if (!connected_) {
    errno = ENOTCONN;
    fail(Op::kConnect);
    return -1;
  }
  const RegisterChannel& o = config_.output;
  const RegisterChannel& m = config_.measurement;
  const int out_address = o.address + offset, in_address = m.address + offset;
  int done = 0;
  if (write && read && config_.write_read) {
    const std::int64_t t0 = monotonic_ns();
    if (modbus_write_and_read_registers(ctx_, out_address, o.registers(), out, in_address,
                                        m.registers(), in) != m.registers()) {
      fail(Op::kWriteRead);
      return -1;
    }
    rtt_ns[done++] = monotonic_ns() - t0;
    return done;
  }
  if (write) {
    const std::int64_t t0 = monotonic_ns();
    const int rc = o.registers() == 1 ? modbus_write_register(ctx_, out_address, out[0])
                                      : modbus_write_registers(ctx_, out_address, 2, out);
    if (rc != 1 && rc != 2) {
      fail(Op::kWrite);
      return -1;
    }
    rtt_ns[done++] = monotonic_ns() - t0;
  }
  if (read) {
    const std::int64_t t0 = monotonic_ns();
    const int rc = m.table == RegisterTable::kInput
                       ? modbus_read_input_registers(ctx_, in_address, m.registers(), in)
                       : modbus_read_registers(ctx_, in_address, m.registers(), in);
    if (rc != m.registers()) {
      fail(Op::kRead);
      return -1;
    }
    rtt_ns[done++] = monotonic_ns() - t0;
  }
  return done;
}

std::string ModbusLink::describe(Op op, int err, const ModbusDaqConfig& c, int offset) {
  const auto regs = [&](const RegisterChannel& ch) {
    const int a = ch.address + offset;
    return std::string(to_string(ch.table)) + " register" + (ch.registers() > 1 ? "s " : " ") +
           std::to_string(a) + (ch.registers() > 1 ? "-" + std::to_string(a + 1) : "");
  };
  // A stage names the axis whose block failed.
  std::string axis;
  if (op != Op::kConnect && !c.axes.empty() && offset % c.axis_stride == 0) {
    const auto i = static_cast<std::size_t>(offset / c.axis_stride);
    if (i < c.axes.size()) axis = " of axis " + c.axes[i];
  }
  std::string what;
  switch (op) {
    case Op::kNone:
      return "";
    case Op::kConnect:
      what = "connecting to " + c.endpoint();
      break;
    case Op::kWrite:
      what = "writing " + regs(c.output);
      break;
    case Op::kRead:
      what = "reading " + regs(c.measurement);
      break;
    case Op::kWriteRead:
      what = "function 23 (write " + regs(c.output) + ", read " + regs(c.measurement) + ")";
      break;
  }
  return what + axis + " (slave " + std::to_string(c.slave_id) + "): " + modbus_strerror(err);
}

}  // namespace hystbench::drivers::details
