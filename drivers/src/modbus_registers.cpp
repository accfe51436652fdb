#include "hystbench/drivers/modbus_registers.hpp"

#include <cmath>
#include <iterator>

namespace hystbench::drivers {

std::string_view to_string(RegisterTable t) noexcept {
  return t == RegisterTable::kHolding ? "holding" : "input";
}

namespace {
/// Each format's name and count range, in RegisterFormat order.
struct FormatRange {
  std::string_view name;
  std::int64_t min, max;
};
constexpr FormatRange kFormats[] = {{"u16", 0, UINT16_MAX},
                                    {"s16", INT16_MIN, INT16_MAX},
                                    {"u32", 0, UINT32_MAX},
                                    {"s32", INT32_MIN, INT32_MAX}};

const FormatRange* range(RegisterFormat f) noexcept {
  const auto i = static_cast<std::size_t>(f);
  return i < std::size(kFormats) ? &kFormats[i] : nullptr;
}
}  // namespace

std::string_view to_string(RegisterFormat f) noexcept {
  const FormatRange* r = range(f);
  return r ? r->name : "unknown";
}

std::int64_t RegisterChannel::count_min() const noexcept {
  const FormatRange* r = range(format);
  return r ? r->min : 0;
}

std::int64_t RegisterChannel::count_max() const noexcept {
  const FormatRange* r = range(format);
  return r ? r->max : 0;
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
