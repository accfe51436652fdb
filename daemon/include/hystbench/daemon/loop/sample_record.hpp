#pragma once
// One control-loop sample as the loop thread logs it: a fixed-size POD, copied into an SpscRing
// and written as one CSV row by SampleLogWriter (column names in parentheses).
// Times are CLOCK_MONOTONIC nanoseconds relative to the run's start (first deadline = 0).
// Units: reference and outputs in µm, voltages in V.
#include <cstdint>
#include <limits>
#include <type_traits>

namespace hystbench::daemon {

/// Bits of SampleRecord::flags. Several may be set in one sample.
enum SampleFlag : std::uint32_t {
  kSampleOutputClamped = 1u << 0,      ///< u_out was clamped to [limits.u_min, limits.u_max]
  kSampleSlewLimited = 1u << 1,        ///< u_out was rate-limited (limits.slew_v_per_s)
  kSampleReferenceLimited = 1u << 2,   ///< reference was clipped to [limits.y_min, limits.y_max]
  kSampleFeedbackSaturated = 1u << 3,  ///< u_fb hit [pid.u_fb_min, pid.u_fb_max]
  kSampleOverrun = 1u << 4,            ///< this tick's work ran past the next deadline
  kSampleFault = 1u << 5,              ///< the driver reported an error / fault this tick
  kSampleStale = 1u << 6,              ///< the measurement was not fresh this tick
  /// No reference was followed this tick (an open-loop drive: identify's excitation, a track's
  /// precondition sweep); the logged yr is then the model's output y_model.
  kSampleOpenLoop = 1u << 7,
};

struct SampleRecord {
  std::uint64_t index = 0;        ///< tick number on the loop's grid (index)
  std::int64_t scheduled_ns = 0;  ///< deadline of this tick (t_scheduled_ns; t = this in s)
  std::int64_t wake_ns = 0;       ///< when the loop thread actually woke (t_wake_ns)
  std::int64_t exec_ns = 0;       ///< work time of the tick, wake to done (exec_ns)
  double reference = 0.0;         ///< reference position y_ref [µm] (yr); see kSampleOpenLoop
  double u_ff = 0.0;              ///< feedforward (inverse model) output [V] (u_ff)
  double u_fb = 0.0;              ///< feedback (PID) output [V] (u_fb)
  double u_out = 0.0;             ///< command sent to the driver after limits [V] (u)
  double y_measured = 0.0;        ///< measured position [µm] (y)
  double y_model = std::numeric_limits<double>::quiet_NaN();  ///< model output [µm], NaN=none
  std::uint32_t flags = 0;                                    ///< SampleFlag bits (flags)
};

static_assert(std::is_trivially_copyable_v<SampleRecord> && std::is_standard_layout_v<SampleRecord>,
              "SampleRecord must stay a POD: it is memcpy'd through the log ring");

}  // namespace hystbench::daemon
