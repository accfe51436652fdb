#pragma once
// Everything one run needs inside the loop, allocated by the control thread before the run and
// handed to the loop whole, so the loop itself never allocates. The loop writes progress and the
// outcome into it; the control thread reads them after the loop hands the program back.
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/stage_decoupling.hpp"
#include "hystbench/daemon/loop/loop_statistics.hpp"
#include "hystbench/daemon/loop/oscillation_detector.hpp"
#include "hystbench/daemon/loop/run_drive.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"

namespace hystbench::daemon {

/// identify: the built-in excitation, then a fit; track: a reference through a compensator;
/// excite: a user's drive, open loop, logged for fit and diagnose; frf: the multisines that
/// measure the stage's frequency responses, open loop.
enum class RunKind { kIdentify, kTrack, kExcite, kFrequencyResponse };
enum class RunEnd { kCompleted, kStopped, kAborted, kFault };
const char* to_string(RunKind kind) noexcept;
const char* to_string(RunEnd end) noexcept;

/// The samples a run keeps for its fit and result, preallocated before the run to `capacity`;
/// the loop fills [0, count). Units: u [V], y and yr [µm].
struct RunRecords {
  std::vector<double> u, y, yr;
  /// identify: per kept sample, the fresh reading's response_ticks, or kNoFreshReading (empty =
  /// not kept).
  std::vector<std::uint32_t> response;
  static constexpr std::uint32_t kNoFreshReading = 0xffffffffu;
  std::uint64_t capacity = 0;
  std::uint64_t count = 0;  ///< written by the loop
};

/// What the loop counted going wrong or being limited during the run (written by the loop).
struct RunCounters {
  std::uint64_t overruns = 0, clamps = 0, slew_limits = 0, reference_clips = 0;
  std::uint64_t stale_reads = 0, log_drops = 0;
};

/// An error's running figures over its scored samples [µm] (written by the loop).
struct ErrorFigures {
  double sum = 0.0, sum2 = 0.0, max = 0.0;
  std::uint64_t samples = 0;
  std::uint64_t max_index = 0;  ///< the run sample (the log's `index`) where `max` fell

  /// Adds one scored sample's error e at run sample k. Real-time safe.
  void add(double e, std::uint64_t k) noexcept {
    sum += e;
    sum2 += e * e;
    if (std::abs(e) > max) max = std::abs(e), max_index = k;
    ++samples;
  }
  /// The mean error [µm]; 0 before any sample.
  double mean() const noexcept { return samples > 0 ? sum / static_cast<double>(samples) : 0.0; }
  /// The rms error [µm]; 0 before any sample.
  double rms() const noexcept {
    return samples > 0 ? std::sqrt(sum2 / static_cast<double>(samples)) : 0.0;
  }
};

struct RunProgram {
  // ---- set by the control thread before submit() ----
  std::string run_id;
  RunKind kind = RunKind::kTrack;
  double dt_s = 0.0;  ///< the loop's period [s] (BenchLoop::submit() sets it)
  std::uint64_t total_samples = 0;
  /// The open-loop drive played from the run's first tick, one value per sample [V]: the whole
  /// run for identify, excite and frf, track's prefix (the precondition sweep).
  std::vector<double> excitation;
  /// The kind's drive from the tick after the excitation on (RunDrive; track's is TrackDrive);
  /// null for a run that is its excitation alone (total_samples == excitation.size()).
  std::unique_ptr<RunDrive> drive;
  /// The active model, configured at the loop's period and relaxed at the run's first output:
  /// stepped every tick with the drive actually applied, its output is y_model (absent = NaN).
  std::optional<compensation::ActuatorModel> model;
  /// The drive's feedback sees no error before this tick (its loop holds at 0), and the
  /// oscillation watch starts here: track's is its reference's first tick, after the sweep.
  std::uint64_t feedback_from = 0;
  /// A run with feedback: watches the error from feedback_from on, and faults the run to the
  /// safe output when the loop oscillates (the loop writes its trip).
  std::optional<OscillationDetector> oscillation;
  /// Samples before this index are left out of the error figures (start-up transient).
  std::uint64_t metrics_from = 0;
  /// y - y_model is scored from max(metrics_from, this): where the drive has swept the range
  /// since the run began, so the model's state no longer depends on the one it started in (an
  /// identify run's major loop: its settle and precondition start from wherever the last run
  /// left the actuator, which the model, relaxed at the run's first output, does not know).
  std::uint64_t model_metrics_from = 0;
  /// Keys merged into the run's result: what the run was built with (compensator, feedback),
  /// set by the control thread, never touched by the loop.
  nlohmann::json summary = nlohmann::json::object();
  /// The active model's identified input delay [ticks]: the stuck-sensor detector waits this
  /// much longer for the reading to answer the output.
  std::uint64_t response_delay_ticks = 0;
  /// The per-run log (may be null in unit tests). On a stage, axis 0's holds every axis's
  /// columns (its row_records() = axes()); the other axes' stay null.
  std::unique_ptr<SampleLogWriter> log;
  /// A stage of several axes: the run's axes after the first (1 .. axes() - 1, in the driver's
  /// order), each a program of this one's kind, length and windows, stepped in the same tick as
  /// it (one write and one read of every axis). Empty: one axis. A driver's axes beyond the
  /// run's hold their safe output.
  std::vector<std::unique_ptr<RunProgram>> stage_axes;
  /// A stage's coupling (axis 0's program): each tick the axes' y_model, their own displacements,
  /// become the stage's prediction (I + K) y_model, which the log, the model error and each
  /// axis's drive see. Absent: each axis's y_model is its own.
  std::optional<compensation::StageDecoupler> coupling;
  /// The run's axes (1 + stage_axes) and axis a's program (0 = this one). Real-time safe.
  std::size_t axes() const noexcept { return stage_axes.size() + 1; }
  RunProgram& axis(std::size_t a) noexcept { return a == 0 ? *this : *stage_axes[a - 1]; }
  const RunProgram& axis(std::size_t a) const noexcept {
    return a == 0 ? *this : *stage_axes[a - 1];
  }
  RunRecords records;

  // ---- written by the loop thread ----
  std::atomic<std::uint64_t> done{0};  ///< samples completed (any thread may read)
  RunEnd end = RunEnd::kCompleted;
  /// Why the run ended, in words (a completed run's too): a static string, or one its loop keeps
  /// while it lives.
  const char* end_reason = "";
  RunCounters counters;
  ErrorFigures error;        ///< tracking error, from metrics_from on
  ErrorFigures model_error;  ///< y - y_model, from model_metrics_from on (see there)
  LoopStatistics stats;      ///< this run's loop timing
};

}  // namespace hystbench::daemon
