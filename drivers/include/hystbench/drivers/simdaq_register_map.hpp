#pragma once
// The register map of hystbench-simdaq, the Modbus server that wraps the simulated actuator
// (documented in docs/drivers.md). Addresses are 0-based (PDU addressing; mbpoll -0).
// Words of 32-bit values: high word first. Positions in nanometres, outputs in millivolts or
// DAC codes (0..65535 over the actuator's input range, default 0..150 V).
// A stage of several axes (hystbench-simdaq --stage): axis i's registers are the ones below at
// i * kAxisBlock in both tables (its own output, position, watchdog and status); input register
// kIrAxes of the first block says how many axes there are.
#include <cstdint>

namespace hystbench::drivers::simdaq {

// Holding registers (read/write).
inline constexpr int kHrOutputCode = 0;     ///< u16 DAC code: writes set the output
inline constexpr int kHrOutputMv = 1;       ///< s32 (1-2) millivolts: writes set the output
inline constexpr int kHrWatchdogMs = 3;     ///< u16: no output write for this long -> safe output
inline constexpr int kHrPositionNm16 = 10;  ///< u16 position [nm] (mirror of IR 0, for fn 23)
inline constexpr int kHrPositionNm = 11;    ///< s32 (11-12) position [nm] (mirror of IR 1-2)
inline constexpr int kHoldingCount = 16;

// Input registers (read only).
inline constexpr int kIrPositionNm16 = 0;  ///< u16 position [nm], clamped to 0..65535
inline constexpr int kIrPositionNm = 1;    ///< s32 (1-2) position [nm]
inline constexpr int kIrSamples = 3;       ///< u32 (3-4) simulation samples since start
inline constexpr int kIrAppliedCode = 5;   ///< u16 DAC code applied now (safe when tripped)
inline constexpr int kIrStatus = 6;        ///< bit 0 watchdog tripped, bit 1 output clamped
inline constexpr int kIrIdent = 7;         ///< 0x4842 ("HB")
inline constexpr int kIrMapVersion = 8;    ///< 1
inline constexpr int kIrAxes = 9;          ///< u16 axes served (first block; 1 without a stage)
inline constexpr int kInputCount = 16;

/// Registers from one axis's block to the next, in both tables ([driver.modbus] axis_stride).
inline constexpr int kAxisBlock = 16;
static_assert(kAxisBlock >= kHoldingCount && kAxisBlock >= kInputCount);

inline constexpr std::uint16_t kIdent = 0x4842;
inline constexpr std::uint16_t kStatusWatchdog = 0x1;
inline constexpr std::uint16_t kStatusClamped = 0x2;

}  // namespace hystbench::drivers::simdaq
