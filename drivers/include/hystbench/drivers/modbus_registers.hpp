#pragma once
// One value carried in Modbus registers: where it is (table, 0-based PDU address), how it is
// encoded (16 or 32 bit, signed or unsigned, word order of a 32-bit pair) and its linear
// scaling to physical units:  physical = offset + scale * count.
// encode()/decode() are real-time safe (no allocation, no exceptions).
#include <cstdint>
#include <string_view>

namespace hystbench::drivers {

enum class RegisterTable : std::uint8_t { kHolding, kInput };
enum class RegisterFormat : std::uint8_t { kU16, kS16, kU32, kS32 };
/// Order of the two 16-bit words of a 32-bit value: kHighFirst ("big", Modbus convention,
/// the high word at the lower address) or kLowFirst ("little").
enum class WordOrder : std::uint8_t { kHighFirst, kLowFirst };

std::string_view to_string(RegisterTable t) noexcept;
std::string_view to_string(RegisterFormat f) noexcept;

struct RegisterChannel {
  RegisterTable table = RegisterTable::kHolding;
  int address = 0;  ///< 0-based register address (PDU addressing) [0, 65535]
  RegisterFormat format = RegisterFormat::kU16;
  WordOrder word_order = WordOrder::kHighFirst;
  double scale = 1.0;   ///< physical units per count, != 0
  double offset = 0.0;  ///< physical value at count 0

  /// 1 or 2.
  int registers() const noexcept {
    return format == RegisterFormat::kU32 || format == RegisterFormat::kS32 ? 2 : 1;
  }
  /// Smallest and largest count of the format.
  std::int64_t count_min() const noexcept;
  std::int64_t count_max() const noexcept;
  /// The count for `physical` (rounded to nearest, clamped to the format's range).
  std::int64_t to_count(double physical) const noexcept;
  double to_physical(std::int64_t count) const noexcept { return offset + scale * count; }
  /// Writes registers() words for `physical`; returns the count written.
  std::int64_t encode(double physical, std::uint16_t* regs) const noexcept;
  /// The physical value of registers() words.
  double decode(const std::uint16_t* regs) const noexcept;
  /// The count held in registers() words.
  std::int64_t decode_count(const std::uint16_t* regs) const noexcept;
};

}  // namespace hystbench::drivers
