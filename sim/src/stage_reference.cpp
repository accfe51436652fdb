#include "hystbench/sim/stage_reference.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "details/field_checks.hpp"

namespace hystbench::sim {

namespace {

// Every message starts with the field path: "<field>: <what is wrong>".
// Inside the unnamed namespace, so that a unity batch's other files' helpers of the same name
// overload these instead of hiding them.
using details::fail;

/// A constant at the middle of `range`: a sine of no amplitude.
SignalSpec held(double middle) {
  SignalSpec s;
  s.kind = SignalKind::kSine;
  s.amplitude = 0.0;
  s.offset = middle;
  return s;
}

std::size_t axes_moved(const StageReferenceSpec& spec) {
  return spec.kind == StageReferenceKind::kLissajous ? spec.frequencies_hz.size() : 2;
}

void validate(const StageReferenceSpec& spec, std::span<const AxisRange> ranges) {
  const std::size_t frequencies = spec.kind == StageReferenceKind::kRaster   ? 2
                                  : spec.kind == StageReferenceKind::kSpiral ? 1
                                                                             : 0;
  if (frequencies > 0 && spec.frequencies_hz.size() != frequencies) {
    fail("frequencies_hz", std::string(to_string(spec.kind)) + " takes " +
                               std::to_string(frequencies) + ", got " +
                               std::to_string(spec.frequencies_hz.size()));
  }
  if (spec.kind == StageReferenceKind::kLissajous && spec.frequencies_hz.size() < 2) {
    fail("frequencies_hz", "lissajous takes one per axis it moves, at least two");
  }
  for (std::size_t i = 0; i < spec.frequencies_hz.size(); ++i) {
    const double f = spec.frequencies_hz[i];
    if (!(std::isfinite(f) && f > 0.0)) {
      fail("frequencies_hz[" + std::to_string(i) + "]", "must be > 0");
    }
  }
  if (!(spec.span_fraction > 0.0 && spec.span_fraction <= 1.0)) {
    fail("span_fraction", "must be in (0, 1]");
  }
  if (!(std::isfinite(spec.duration_s) && spec.duration_s > 0.0)) {
    fail("duration_s", "must be > 0");
  }
  if (ranges.size() < axes_moved(spec)) {
    fail("axes", std::string(to_string(spec.kind)) + " moves " + std::to_string(axes_moved(spec)) +
                     " axes, the stage has " + std::to_string(ranges.size()));
  }
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (!(std::isfinite(ranges[i].min) && std::isfinite(ranges[i].max) &&
          ranges[i].max > ranges[i].min)) {
      fail("ranges[" + std::to_string(i) + "]", "max must be greater than min");
    }
  }
}

}  // namespace

std::string_view to_string(StageReferenceKind kind) noexcept {
  switch (kind) {
    case StageReferenceKind::kLissajous:
      return "lissajous";
    case StageReferenceKind::kSpiral:
      return "spiral";
    case StageReferenceKind::kRaster:
      break;
  }
  return "raster";
}

StageReferenceKind stage_reference_kind_from_string(std::string_view name) {
  for (const auto kind :
       {StageReferenceKind::kRaster, StageReferenceKind::kLissajous, StageReferenceKind::kSpiral}) {
    if (name == to_string(kind)) return kind;
  }
  throw std::invalid_argument("unknown stage reference \"" + std::string(name) +
                              "\" (valid: raster, lissajous, spiral)");
}

std::vector<SignalSpec> stage_reference(const StageReferenceSpec& spec,
                                        std::span<const AxisRange> ranges) {
  validate(spec, ranges);
  std::vector<SignalSpec> out;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double middle = 0.5 * (ranges[i].min + ranges[i].max);
    const double amplitude = 0.5 * spec.span_fraction * (ranges[i].max - ranges[i].min);
    SignalSpec s = held(middle);
    if (i < axes_moved(spec)) {
      s.amplitude = amplitude;
      switch (spec.kind) {
        case StageReferenceKind::kRaster:
          s.kind = SignalKind::kTriangle;
          s.frequency_hz = spec.frequencies_hz[i];
          s.phase_rad = -0.5 * std::numbers::pi;  // from the bottom, rising
          break;
        case StageReferenceKind::kLissajous:
          s.frequency_hz = spec.frequencies_hz[i];
          break;
        case StageReferenceKind::kSpiral:
          s.kind = SignalKind::kDecayingSine;
          s.frequency_hz = spec.frequencies_hz[0];
          s.duration_s = spec.duration_s;
          s.phase_rad = i == 0 ? 0.0 : 0.5 * std::numbers::pi;  // a sine and a cosine
          break;
      }
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace hystbench::sim
