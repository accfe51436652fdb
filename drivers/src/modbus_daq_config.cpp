#include "hystbench/drivers/modbus_daq_config.hpp"

#include <cmath>
#include <stdexcept>

#include "details/json_params.hpp"

namespace hystbench::drivers {

namespace {

using details::ParamError;
using details::Params;

RegisterChannel parse_channel(const Params& p, const RegisterChannel& defaults, bool is_output) {
  p.allow_only(is_output
                   ? std::initializer_list<const char*>{"table", "address", "format", "word_order",
                                                        "scale", "offset", "min_v", "max_v"}
                   : std::initializer_list<const char*>{"table", "address", "format", "word_order",
                                                        "scale", "offset"});
  RegisterChannel c = defaults;
  const std::string table =
      is_output ? p.choice("table", "holding", {"holding"})
                : p.choice("table", std::string(to_string(c.table)), {"input", "holding"});
  c.table = table == "input" ? RegisterTable::kInput : RegisterTable::kHolding;
  c.address = static_cast<int>(p.integer("address", c.address, 0, 65535));
  const std::string format =
      p.choice("format", std::string(to_string(c.format)), {"u16", "s16", "u32", "s32"});
  c.format = format == "u16"   ? RegisterFormat::kU16
             : format == "s16" ? RegisterFormat::kS16
             : format == "u32" ? RegisterFormat::kU32
                               : RegisterFormat::kS32;
  const std::string order = p.choice(
      "word_order", c.word_order == WordOrder::kHighFirst ? "big" : "little", {"big", "little"});
  c.word_order = order == "big" ? WordOrder::kHighFirst : WordOrder::kLowFirst;
  c.scale = p.number("scale", c.scale, -1e12, 1e12);
  if (c.scale == 0.0) throw ParamError(p.key_path("scale") + ": must not be 0");
  c.offset = p.number("offset", c.offset, -1e12, 1e12);
  if (c.address + c.registers() - 1 > 65535) {
    throw ParamError(p.key_path("address") + ": a 32-bit value at 65535 runs past the table");
  }
  return c;
}

/// The TCP keys on an RTU line and the RTU keys on TCP are errors naming them.
void refuse_other_transports_keys(const Params& p, bool tcp) {
  for (const char* k : {"host", "port"}) {
    if (!tcp && p.has(k)) throw ParamError(p.key_path(k) + ": only for transport = \"tcp\"");
  }
  for (const char* k : {"device", "baud", "parity", "data_bits", "stop_bits"}) {
    if (tcp && p.has(k)) throw ParamError(p.key_path(k) + ": only for transport = \"rtu\"");
  }
}

/// The [output] table: its register, and its range in volts, which the format must hold.
void parse_output(const Params& out, ModbusDaqConfig& c) {
  c.output = parse_channel(out, c.output, true);
  c.output_min_v = out.number("min_v", c.output_min_v, -1e6, 1e6);
  c.output_max_v = out.number("max_v", c.output_max_v, -1e6, 1e6);
  if (!(c.output_max_v > c.output_min_v)) {
    throw ParamError(out.key_path("max_v") + ": must be greater than min_v");
  }
  for (const double v : {c.output_min_v, c.output_max_v}) {
    const double count = (v - c.output.offset) / c.output.scale;
    if (count < static_cast<double>(c.output.count_min()) - 0.5 ||
        count > static_cast<double>(c.output.count_max()) + 0.5) {
      throw ParamError(out.path() + ": " + std::to_string(v) + " V needs count " +
                       std::to_string(count) + ", beyond the " +
                       std::string(to_string(c.output.format)) + " range");
    }
  }
}

/// The `axes` names and `axis_stride`: every axis's block within the register tables.
void parse_axes(const Params& p, ModbusDaqConfig& c) {
  c.axes = p.axis_names("axes");
  if (p.has("axis_stride") && !p.has("axes")) {
    throw ParamError(p.key_path("axis_stride") + ": only with axes (a stage of several axes)");
  }
  c.axis_stride = static_cast<int>(p.integer("axis_stride", c.axis_stride, 1, 65535));
  const std::size_t last = c.axis_count() - 1;
  for (const auto& [name, ch] : {std::pair{"output", &c.output}, {"measurement", &c.measurement}}) {
    if (last > 0 && c.axis_stride < ch->registers()) {
      throw ParamError(p.key_path("axis_stride") + ": " + std::to_string(c.axis_stride) +
                       " register(s) would overlap the axes' " + name + " values of " +
                       std::to_string(ch->registers()) + " registers");
    }
    const int end = ch->address + c.axis_offset(last) + ch->registers() - 1;
    if (end > 65535) {
      throw ParamError(p.key_path("axes") + ": axis \"" + c.axes[last] + "\"'s " + name +
                       " would end at register " + std::to_string(end) +
                       ", past the table (65535): lower axis_stride or the address");
    }
  }
}

}  // namespace

std::string ModbusDaqConfig::endpoint() const {
  if (transport == Transport::kTcp) return "tcp " + host + ":" + std::to_string(port);
  return "rtu " + device + " " + std::to_string(baud) + " " + std::to_string(data_bits) + parity +
         std::to_string(stop_bits);
}

double ModbusDaqConfig::rtu_wire_time_s() const noexcept {
  if (transport != Transport::kRtu) return 0.0;
  const int w = output.registers(), r = measurement.registers();
  // Request + response bytes (address, function, data, CRC) of each transaction in a tick.
  int bytes = 0;
  int frames = 0;
  if (write_read) {
    bytes += (13 + 2 * w) + (5 + 2 * r);
    frames += 2;
  } else {
    bytes += (w == 1 ? 8 + 8 : 9 + 2 * w + 8) + (8 + 5 + 2 * r);
    frames += 4;
  }
  const int bits_per_char = 1 + data_bits + (parity == 'N' ? 0 : 1) + stop_bits;
  // Each frame is followed by at least 3.5 character times of silence; each axis has its own.
  return static_cast<double>(axis_count()) * (bytes + 3.5 * frames) * bits_per_char /
         static_cast<double>(baud);
}

ModbusDaqConfig parse_modbus_daq_config(const nlohmann::json& params) {
  try {
    const Params p(params, "driver.modbus");
    p.allow_only({"transport",
                  "host",
                  "port",
                  "device",
                  "baud",
                  "parity",
                  "data_bits",
                  "stop_bits",
                  "slave_id",
                  "response_timeout_ms",
                  "io",
                  "write_read",
                  "max_rate_hz",
                  "max_stale_reads",
                  "max_failed_transactions",
                  "reconnect_interval_ms",
                  "safe_output_v",
                  "output",
                  "measurement",
                  "axes",
                  "axis_stride"});
    ModbusDaqConfig c;
    c.transport = p.choice("transport", "tcp", {"tcp", "rtu"}) == "tcp"
                      ? ModbusDaqConfig::Transport::kTcp
                      : ModbusDaqConfig::Transport::kRtu;
    const bool tcp = c.transport == ModbusDaqConfig::Transport::kTcp;
    refuse_other_transports_keys(p, tcp);
    c.host = p.string("host", c.host);
    if (c.host.empty()) throw ParamError(p.key_path("host") + ": must not be empty");
    c.port = static_cast<int>(p.integer("port", c.port, 1, 65535));
    c.device = p.string("device", c.device);
    c.baud = static_cast<int>(p.integer("baud", c.baud, 300, 4000000));
    const std::string parity = p.choice("parity", "none", {"none", "even", "odd"});
    c.parity = parity == "none" ? 'N' : parity == "even" ? 'E' : 'O';
    c.data_bits = static_cast<int>(p.integer("data_bits", 8, 7, 8));
    c.stop_bits = static_cast<int>(p.integer("stop_bits", 1, 1, 2));
    c.slave_id = static_cast<int>(p.integer("slave_id", 1, tcp ? 0 : 1, tcp ? 255 : 247));
    c.response_timeout_ms = p.number("response_timeout_ms", c.response_timeout_ms, 0.0, 10000.0);
    if (c.response_timeout_ms <= 0.0) {
      throw ParamError(p.key_path("response_timeout_ms") + ": must be > 0");
    }
    c.io = p.choice("io", "thread", {"thread", "loop"}) == "thread"
               ? ModbusDaqConfig::IoMode::kThread
               : ModbusDaqConfig::IoMode::kLoop;
    c.write_read = p.boolean("write_read", c.write_read);
    c.max_rate_hz = p.number("max_rate_hz", 0.0, 0.0, 20000.0);
    if (p.has("max_rate_hz") && c.max_rate_hz <= 0.0) {
      throw ParamError(p.key_path("max_rate_hz") + ": must be > 0");
    }
    c.max_stale_reads = static_cast<std::uint64_t>(p.integer("max_stale_reads", 0, 1, 1000000000));
    c.max_failed_transactions =
        static_cast<std::uint64_t>(p.integer("max_failed_transactions", 3, 1, 1000000000));
    c.reconnect_interval_ms = p.number("reconnect_interval_ms", 200.0, 1.0, 60000.0);

    parse_output(p.table("output"), c);
    c.measurement = parse_channel(p.table("measurement"), c.measurement, false);
    parse_axes(p, c);
    c.safe_output_v = p.number("safe_output_v", c.output_min_v, -1e6, 1e6);
    if (c.safe_output_v < c.output_min_v || c.safe_output_v > c.output_max_v) {
      throw ParamError(p.key_path("safe_output_v") + ": must be within [output.min_v, " +
                       "output.max_v]");
    }
    if (c.write_read && c.measurement.table != RegisterTable::kHolding) {
      throw ParamError(p.key_path("write_read") +
                       ": function 23 reads holding registers; set measurement.table = "
                       "\"holding\" or write_read = false");
    }
    if (c.max_rate_hz == 0.0) {
      const double wire = c.rtu_wire_time_s();
      c.max_rate_hz = wire > 0.0 ? std::min(20000.0, std::floor(1.0 / wire)) : 20000.0;
    }
    return c;
  } catch (const ParamError& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace hystbench::drivers
