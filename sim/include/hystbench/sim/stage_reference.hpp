#pragma once
// The built-in references of a stage of several axes, each axis's as a SignalSpec
// (signal_generator.hpp) over its own range [µm]:
//   raster     the fast axis (0) a triangle at frequencies_hz[0], the slow axis (1) a triangle at
//              frequencies_hz[1]: one line per half period of the fast axis; both start at the
//              bottom of their span;
//   lissajous  axis i a sine at frequencies_hz[i], each starting at its middle, rising;
//   spiral     axes 0 and 1 a sine and a cosine at frequencies_hz[0] whose radius shrinks
//              linearly from the span's edge to the middle over duration_s, then holds it;
// over span_fraction of each axis's range about its middle. Axes beyond those the kind moves
// hold their middle. Allocates and throws: not for the real-time path (the generators' value()
// is).
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "hystbench/sim/signal_generator.hpp"

namespace hystbench::sim {

enum class StageReferenceKind { kRaster, kLissajous, kSpiral };

/// "raster", "lissajous", "spiral".
std::string_view to_string(StageReferenceKind kind) noexcept;
/// Throws std::invalid_argument listing the valid names.
StageReferenceKind stage_reference_kind_from_string(std::string_view name);

struct AxisRange {
  double min = 0.0;  ///< [µm]
  double max = 1.0;  ///< [µm], > min
};

struct StageReferenceSpec {
  StageReferenceKind kind = StageReferenceKind::kRaster;
  /// raster: {fast, slow}; lissajous: one per axis it moves (at least two); spiral: {turns per
  /// second}. Each > 0 [Hz].
  std::vector<double> frequencies_hz = {10.0, 0.1};
  double span_fraction = 0.8;  ///< of each axis's range, in (0, 1]
  double duration_s = 10.0;    ///< spiral: from the edge to the middle, > 0 [s]
};

/// One SignalSpec per axis of `ranges`. Throws std::invalid_argument naming the field: fewer
/// axes than the kind moves (raster and spiral two, lissajous one per frequency), a frequency
/// <= 0 or not finite, a span outside (0, 1], a duration <= 0, an empty range.
std::vector<SignalSpec> stage_reference(const StageReferenceSpec& spec,
                                        std::span<const AxisRange> ranges);

}  // namespace hystbench::sim
