// Register encodings of the Modbus DAQ driver: formats, word order, scaling, clamping.
#include "hystbench/drivers/modbus_registers.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hd = hystbench::drivers;

namespace {
hd::RegisterChannel channel(hd::RegisterFormat f, hd::WordOrder o, double scale = 1.0,
                            double offset = 0.0) {
  return {hd::RegisterTable::kHolding, 0, f, o, scale, offset};
}
}  // namespace

TEST(ModbusRegisters, ThirtyTwoBitWordOrderPutsTheHighWordWhereConfigured) {
  std::uint16_t r[2];
  channel(hd::RegisterFormat::kS32, hd::WordOrder::kHighFirst).encode(-2.0, r);
  EXPECT_EQ(r[0], 0xffff);
  EXPECT_EQ(r[1], 0xfffe);
  channel(hd::RegisterFormat::kU32, hd::WordOrder::kHighFirst).encode(0x12345678, r);
  EXPECT_EQ(r[0], 0x1234);
  EXPECT_EQ(r[1], 0x5678);
  channel(hd::RegisterFormat::kU32, hd::WordOrder::kLowFirst).encode(0x12345678, r);
  EXPECT_EQ(r[0], 0x5678);
  EXPECT_EQ(r[1], 0x1234);
  const std::uint16_t low_first[2] = {0x5678, 0x1234};
  EXPECT_EQ(channel(hd::RegisterFormat::kU32, hd::WordOrder::kLowFirst).decode_count(low_first),
            0x12345678);
}

TEST(ModbusRegisters, SignedFormatsDecodeNegativeCounts) {
  const std::uint16_t m1[2] = {0xffff, 0xffff};
  EXPECT_EQ(channel(hd::RegisterFormat::kS16, hd::WordOrder::kHighFirst).decode_count(m1), -1);
  EXPECT_EQ(channel(hd::RegisterFormat::kU16, hd::WordOrder::kHighFirst).decode_count(m1), 65535);
  EXPECT_EQ(channel(hd::RegisterFormat::kS32, hd::WordOrder::kLowFirst).decode_count(m1), -1);
  EXPECT_EQ(channel(hd::RegisterFormat::kU32, hd::WordOrder::kLowFirst).decode_count(m1),
            4294967295LL);
}

TEST(ModbusRegisters, ScalingRoundTripsWithinHalfACount) {
  // 0..150 V over a 16-bit DAC.
  const auto c = channel(hd::RegisterFormat::kU16, hd::WordOrder::kHighFirst, 150.0 / 65535.0);
  for (double v = 0.0; v <= 150.0; v += 0.37) {
    std::uint16_t r[1];
    c.encode(v, r);
    EXPECT_NEAR(c.decode(r), v, 0.5 * 150.0 / 65535.0 + 1e-12);
  }
  // Offset: -10..10 V as a signed count in mV.
  const auto s = channel(hd::RegisterFormat::kS16, hd::WordOrder::kHighFirst, 0.001, 0.0);
  std::uint16_t r[1];
  s.encode(-7.5, r);
  EXPECT_EQ(static_cast<std::int16_t>(r[0]), -7500);
}

TEST(ModbusRegisters, OutOfRangeAndNanClampToTheFormat) {
  const auto c = channel(hd::RegisterFormat::kU16, hd::WordOrder::kHighFirst, 150.0 / 65535.0);
  std::uint16_t r[1];
  EXPECT_EQ(c.encode(200.0, r), 65535);
  EXPECT_EQ(c.encode(-5.0, r), 0);
  EXPECT_EQ(c.encode(std::nan(""), r), 0);
  const auto s = channel(hd::RegisterFormat::kS32, hd::WordOrder::kHighFirst);
  std::uint16_t w[2];
  EXPECT_EQ(s.encode(1e12, w), INT32_MAX);
  EXPECT_EQ(s.encode(-1e12, w), INT32_MIN);
}
