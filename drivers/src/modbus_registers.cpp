#include "hystbench/drivers/modbus_registers.hpp"

#include <cmath>

namespace hystbench::drivers {

std::string_view to_string(RegisterTable t) noexcept {
  return t == RegisterTable::kHolding ? "holding" : "input";
}

std::string_view to_string(RegisterFormat f) noexcept {
  switch (f) {
    case RegisterFormat::kU16:
      return "u16";
    case RegisterFormat::kS16:
      return "s16";
    case RegisterFormat::kU32:
      return "u32";
    case RegisterFormat::kS32:
      return "s32";
  }
  return "unknown";
}

std::int64_t RegisterChannel::count_min() const noexcept {
  switch (format) {
    case RegisterFormat::kS16:
      return INT16_MIN;
    case RegisterFormat::kS32:
      return INT32_MIN;
    default:
      return 0;
  }
}

std::int64_t RegisterChannel::count_max() const noexcept {
  switch (format) {
    case RegisterFormat::kU16:
      return UINT16_MAX;
    case RegisterFormat::kS16:
      return INT16_MAX;
    case RegisterFormat::kU32:
      return UINT32_MAX;
    case RegisterFormat::kS32:
      return INT32_MAX;
  }
  return 0;
}

std::int64_t RegisterChannel::to_count(double physical) const noexcept {
  const double c = std::round((physical - offset) / scale);
  if (!(c >= static_cast<double>(count_min()))) return count_min();  // NaN too
  if (c > static_cast<double>(count_max())) return count_max();
  return static_cast<std::int64_t>(c);
}

std::int64_t RegisterChannel::encode(double physical, std::uint16_t* regs) const noexcept {
  const std::int64_t c = to_count(physical);
  const auto bits = static_cast<std::uint32_t>(static_cast<std::uint64_t>(c) & 0xffffffffu);
  if (registers() == 1) {
    regs[0] = static_cast<std::uint16_t>(bits & 0xffffu);
  } else {
    const auto hi = static_cast<std::uint16_t>(bits >> 16);
    const auto lo = static_cast<std::uint16_t>(bits & 0xffffu);
    regs[0] = word_order == WordOrder::kHighFirst ? hi : lo;
    regs[1] = word_order == WordOrder::kHighFirst ? lo : hi;
  }
  return c;
}

std::int64_t RegisterChannel::decode_count(const std::uint16_t* regs) const noexcept {
  switch (format) {
    case RegisterFormat::kU16:
      return regs[0];
    case RegisterFormat::kS16:
      return static_cast<std::int16_t>(regs[0]);
    case RegisterFormat::kU32:
    case RegisterFormat::kS32: {
      const std::uint32_t hi = word_order == WordOrder::kHighFirst ? regs[0] : regs[1];
      const std::uint32_t lo = word_order == WordOrder::kHighFirst ? regs[1] : regs[0];
      const std::uint32_t bits = (hi << 16) | lo;
      return format == RegisterFormat::kU32 ? static_cast<std::int64_t>(bits)
                                            : static_cast<std::int32_t>(bits);
    }
  }
  return 0;
}

double RegisterChannel::decode(const std::uint16_t* regs) const noexcept {
  return to_physical(decode_count(regs));
}

}  // namespace hystbench::drivers
