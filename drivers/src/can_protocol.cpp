#include "hystbench/drivers/can_protocol.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "details/json_params.hpp"

namespace hystbench::drivers {

using details::ParamError;
using details::Params;

std::string CanFrameId::describe() const {
  char buf[40];
  std::snprintf(buf, sizeof buf, extended ? "0x%08X (extended)" : "0x%03X", id);
  return buf;
}

std::int64_t CanField::count_min() const noexcept {
  return is_signed ? -(std::int64_t{1} << (8 * bytes - 1)) : 0;
}

std::int64_t CanField::count_max() const noexcept {
  return is_signed ? (std::int64_t{1} << (8 * bytes - 1)) - 1
                   : (std::int64_t{1} << (8 * bytes)) - 1;
}

std::int64_t CanField::encode(double value, std::uint8_t* data) const noexcept {
  double c = std::round((value - offset) / scale);
  if (!(c >= static_cast<double>(count_min()))) c = static_cast<double>(count_min());
  if (c > static_cast<double>(count_max())) c = static_cast<double>(count_max());
  const auto count = static_cast<std::int64_t>(c);
  const auto bits = static_cast<std::uint64_t>(count);
  for (int i = 0; i < bytes; ++i) {
    const int shift = 8 * (big_endian ? bytes - 1 - i : i);
    data[start_byte + i] = static_cast<std::uint8_t>((bits >> shift) & 0xffu);
  }
  return count;
}

double CanField::decode(const std::uint8_t* data) const noexcept {
  std::uint64_t bits = 0;
  for (int i = 0; i < bytes; ++i) {
    const int shift = 8 * (big_endian ? bytes - 1 - i : i);
    bits |= static_cast<std::uint64_t>(data[start_byte + i]) << shift;
  }
  std::int64_t count = static_cast<std::int64_t>(bits);
  if (is_signed && (bits >> (8 * bytes - 1)) != 0) count -= std::int64_t{1} << (8 * bytes);
  return offset + scale * static_cast<double>(count);
}

namespace {
can_frame fixed(const CanFrameId& id, const std::vector<std::uint8_t>& data) noexcept {
  can_frame f{};
  f.can_id = id.can_id();
  f.can_dlc = static_cast<std::uint8_t>(data.size());
  std::memcpy(f.data, data.data(), data.size());
  return f;
}
}  // namespace

can_frame CanProtocol::setpoint_frame(double volts) const noexcept {
  can_frame f{};
  f.can_id = setpoint_id.can_id();
  f.can_dlc = static_cast<std::uint8_t>(setpoint_length);
  setpoint.encode(volts, f.data);
  return f;
}

can_frame CanProtocol::feedback_frame(double position_um, std::uint8_t status) const noexcept {
  can_frame f{};
  f.can_id = feedback_id.can_id();
  f.can_dlc = static_cast<std::uint8_t>(feedback_length);
  feedback.encode(position_um, f.data);
  if (status_byte >= 0) f.data[status_byte] = status;
  return f;
}

can_frame CanProtocol::enable_frame() const noexcept { return fixed(enable_id, enable_data); }
can_frame CanProtocol::disable_frame() const noexcept { return fixed(disable_id, disable_data); }

CanProtocol::Decoded CanProtocol::decode_feedback(const can_frame& f, double& position_um,
                                                  std::uint8_t& status) const noexcept {
  if (!feedback_id.matches(f)) return Decoded::kOther;
  if (f.can_dlc != feedback_length) return Decoded::kMalformed;
  position_um = feedback.decode(f.data);
  status = status_byte >= 0 ? f.data[status_byte] : 0;
  return Decoded::kFeedback;
}

int CanProtocol::enable_command(const can_frame& f) const noexcept {
  const auto same = [&](const CanFrameId& id, const std::vector<std::uint8_t>& d) {
    return id.matches(f) && f.can_dlc == d.size() && std::memcmp(f.data, d.data(), d.size()) == 0;
  };
  if (same(enable_id, enable_data)) return 1;
  if (same(disable_id, disable_data)) return 0;
  return -1;
}

bool CanProtocol::decode_setpoint(const can_frame& f, double& volts) const noexcept {
  if (!setpoint_id.matches(f) || f.can_dlc != setpoint_length) return false;
  volts = setpoint.decode(f.data);
  return true;
}

CanProtocol CanProtocol::at_node(std::uint32_t offset) const {
  CanProtocol p = *this;
  for (CanFrameId* id : {&p.setpoint_id, &p.feedback_id, &p.enable_id, &p.disable_id}) {
    id->id += offset;
  }
  return p;
}

void check_can_nodes(const CanProtocol& protocol, std::size_t nodes, std::uint32_t node_step,
                     const std::string& path) {
  const std::uint32_t last = static_cast<std::uint32_t>(nodes - 1) * node_step;
  for (const CanFrameId& id :
       {protocol.setpoint_id, protocol.feedback_id, protocol.enable_id, protocol.disable_id}) {
    const std::uint32_t mask = id.extended ? CAN_EFF_MASK : CAN_SFF_MASK;
    if (id.id + last > mask) {
      throw std::invalid_argument(path + ".node_step: the last axis's frame " + id.describe() +
                                  " + " + std::to_string(last) + " is beyond the id range (" +
                                  CanFrameId{mask, id.extended}.describe() + ")");
    }
  }
  for (std::size_t a = 0; a < nodes; ++a) {
    for (std::size_t b = 0; b < nodes; ++b) {
      const CanFrameId sp = protocol.at_node(static_cast<std::uint32_t>(a) * node_step).setpoint_id;
      const CanFrameId fb = protocol.at_node(static_cast<std::uint32_t>(b) * node_step).feedback_id;
      if (sp.can_id() == fb.can_id()) {
        throw std::invalid_argument(path + ".node_step: axis " + std::to_string(a) +
                                    "'s setpoint id " + sp.describe() + " is axis " +
                                    std::to_string(b) + "'s feedback id");
      }
    }
  }
}

int can_frame_bits(int n, bool extended) noexcept {
  // Worst case with stuff bits (CAN 2.0): 8n + 44 + floor((34 + 8n - 1) / 4) for 11-bit ids,
  // 8n + 64 + floor((54 + 8n - 1) / 4) for 29-bit ids, plus 3 bits of interframe space.
  return extended ? 8 * n + 67 + (54 + 8 * n - 1) / 4 : 8 * n + 47 + (34 + 8 * n - 1) / 4;
}

namespace {

CanFrameId parse_id(const Params& p, CanFrameId id) {
  id.extended = p.boolean("extended", id.extended);
  id.id = static_cast<std::uint32_t>(
      p.integer("id", id.id, 0, id.extended ? CAN_EFF_MASK : CAN_SFF_MASK));
  return id;
}

CanField parse_field(const Params& p, CanField f, int length) {
  f.start_byte = static_cast<int>(p.integer("start_byte", f.start_byte, 0, 7));
  f.bytes = static_cast<int>(p.integer("bytes", f.bytes, 1, 4));
  if (f.bytes == 3) throw ParamError(p.key_path("bytes") + ": must be 1, 2 or 4");
  f.is_signed = p.boolean("signed", f.is_signed);
  f.big_endian =
      p.choice("byte_order", f.big_endian ? "big" : "little", {"little", "big"}) == "big";
  f.scale = p.number("scale", f.scale, -1e12, 1e12);
  if (f.scale == 0.0) throw ParamError(p.key_path("scale") + ": must not be 0");
  f.offset = p.number("offset", f.offset, -1e12, 1e12);
  if (f.start_byte + f.bytes > length) {
    throw ParamError(p.key_path("start_byte") + ": bytes " + std::to_string(f.start_byte) + ".." +
                     std::to_string(f.start_byte + f.bytes - 1) + " do not fit in length " +
                     std::to_string(length));
  }
  return f;
}

}  // namespace

CanProtocol parse_can_protocol(const nlohmann::json& table, const std::string& path) {
  try {
    const Params p(table, path);
    CanProtocol c;
    const Params sp = p.table("setpoint");
    sp.allow_only({"id", "extended", "length", "start_byte", "bytes", "signed", "byte_order",
                   "scale", "offset"});
    c.setpoint_id = parse_id(sp, c.setpoint_id);
    c.setpoint_length = static_cast<int>(sp.integer("length", c.setpoint_length, 1, 8));
    c.setpoint = parse_field(sp, c.setpoint, c.setpoint_length);

    const Params fb = p.table("feedback");
    fb.allow_only({"id", "extended", "length", "start_byte", "bytes", "signed", "byte_order",
                   "scale", "offset", "status_byte", "fault_mask"});
    c.feedback_id = parse_id(fb, c.feedback_id);
    c.feedback_length = static_cast<int>(fb.integer("length", c.feedback_length, 1, 8));
    c.feedback = parse_field(fb, c.feedback, c.feedback_length);
    const int status_default = c.status_byte < c.feedback_length ? c.status_byte : -1;
    c.status_byte = static_cast<int>(fb.integer("status_byte", status_default, -1, 7));
    if (c.status_byte >= c.feedback_length) {
      throw ParamError(fb.key_path("status_byte") + ": beyond length " +
                       std::to_string(c.feedback_length));
    }
    if (c.status_byte >= c.feedback.start_byte &&
        c.status_byte < c.feedback.start_byte + c.feedback.bytes) {
      throw ParamError(fb.key_path("status_byte") + ": overlaps the position field");
    }
    c.fault_mask = static_cast<std::uint8_t>(fb.integer("fault_mask", c.fault_mask, 0, 255));

    for (const char* name : {"enable", "disable"}) {
      const Params t = p.table(name);
      t.allow_only({"id", "extended", "data"});
      const bool en = std::string(name) == "enable";
      CanFrameId& id = en ? c.enable_id : c.disable_id;
      std::vector<std::uint8_t>& data = en ? c.enable_data : c.disable_data;
      id = parse_id(t, id);
      std::vector<std::int64_t> def(data.begin(), data.end());
      const auto bytes = t.integers("data", def, 0, 255);
      if (bytes.size() > 8) throw ParamError(t.key_path("data") + ": at most 8 bytes");
      data.assign(bytes.begin(), bytes.end());
    }
    if (c.setpoint_id.can_id() == c.feedback_id.can_id()) {
      throw ParamError(path + ".feedback.id: the same as setpoint.id");
    }
    return c;
  } catch (const ParamError& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace hystbench::drivers
