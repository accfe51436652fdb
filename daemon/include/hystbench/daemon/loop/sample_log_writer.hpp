#pragma once
// Per-run sample log: the loop thread push()es SampleRecords into a preallocated SPSC ring, a
// writer thread drains it into `<log_dir>/<run_id>.csv`.
//
// File format (pandas `read_csv(path, comment='#')`, MATLAB `readtable(path, 'CommentStyle',
// '#')`, and DataTable::read_csv read it as is):
//   # {"schema":"hystbench.samples/1","run_id":"...","created":"2026-01-01T00:00:00Z"}
//   # {"<key>": ...}                  one line per top-level key of SampleLogOptions::header
//   # {"units": {"t": "s", ...}}
//   # {"flags": {"output_clamped": 1, ...}}
//   # {"columns": ["index", "t", ...]}
//   index,t,t_scheduled_ns,t_wake_ns,exec_ns,yr,u_ff,u_fb,u,y,y_model,flags
//   0,0,0,1520,8300,0,0,0,0,0.0123,NaN,0
// A stage of several axes (SampleLogOptions::axes, 2-6 names) keeps the five time columns once
// and then, per axis in order, its own yr_<name>,u_ff_<name>,u_fb_<name>,u_<name>,y_<name>,
// y_model_<name>,flags_<name>; the loop pushes one record per axis per tick (push_row()).
// Every '#' line is one JSON object; merging the leading ones gives the header
// (read_sample_log_header()). A run may append one after the rows: a replay of a learned drive
// whose lead-in ended early gives where its scored part began (# {"scored_from": k, ...}).
// Doubles are written in the shortest form that reads back to the same bits (std::to_chars),
// NaN / infinities as NaN / Inf / -Inf. Column `t` is t_scheduled_ns in seconds.
// `<log_dir>/latest.csv` is a relative symlink to the newest run's file, replaced atomically
// (symlink to a temporary name, then rename) when a writer is constructed.
//
// Threads: push() from one thread only (the loop); everything else from non-real-time threads.
// The writer thread runs SCHED_OTHER whatever the constructing thread runs; pin the loop to a
// CPU of its own so the writer is not starved.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "hystbench/daemon/loop/sample_record.hpp"
#include "hystbench/daemon/loop/spsc_ring.hpp"

namespace hystbench::daemon {

inline constexpr const char* kSampleLogSchema = "hystbench.samples/1";

struct SampleLogOptions {
  std::filesystem::path log_dir;  ///< created (with parents) when missing
  /// File stem: 1-128 characters of [A-Za-z0-9._-], not starting with '.', not "latest".
  std::string run_id;
  /// Run description (parameters, model, driver, ...): a JSON object; each top-level key
  /// becomes one '# {"key": value}' line. The keys schema, run_id, created, units, flags and
  /// columns are reserved.
  nlohmann::json header = nlohmann::json::object();
  /// Records the ring holds (rounded up to a power of two): at 20 kHz, 65536 = 3.3 s of
  /// slack for the writer thread.
  std::size_t ring_capacity = std::size_t{1} << 16;
  /// How often the writer thread wakes to drain the ring.
  std::chrono::milliseconds poll_interval{10};
  /// How often written rows are handed to the kernel at the latest (and on close()).
  std::chrono::milliseconds flush_interval{500};
  bool update_latest_link = true;
  /// A stage's axis names, in the driver's order: 2-6 of 1-16 characters of [a-z0-9_], each
  /// once. Empty = one axis, the columns above.
  std::vector<std::string> axes;
};

struct SampleLogCounts {
  std::uint64_t written = 0;  ///< rows written to the file
  std::uint64_t dropped = 0;  ///< records that never reached the file (ring full, I/O error)
  std::string error;          ///< first I/O error, empty when none
};

class SampleLogWriter {
 public:
  /// Creates the file (refusing to overwrite one), writes the header, points latest.csv at it
  /// and starts the writer thread. Throws std::invalid_argument for bad options and
  /// std::system_error naming the path when the directory, file or link cannot be made.
  explicit SampleLogWriter(SampleLogOptions options);
  /// Calls close().
  ~SampleLogWriter();
  SampleLogWriter(const SampleLogWriter&) = delete;
  SampleLogWriter& operator=(const SampleLogWriter&) = delete;

  /// Loop thread. Real-time safe (copies into the ring: no allocation, lock or system call).
  /// Returns false and counts a drop when the ring is full or the log is closed.
  bool push(const SampleRecord& record) noexcept { return push_row({&record, 1}); }
  /// One tick of a stage: a record per axis (axes().size() of them; the first one's times are
  /// the row's), all kept or all dropped. Real-time safe.
  bool push_row(std::span<const SampleRecord> records) noexcept;
  /// As push_row(), but a full ring or a closed log is not counted as a drop: the caller tries
  /// again or gives up with push_row(). Real-time safe.
  bool try_push_row(std::span<const SampleRecord> records) noexcept {
    return !closed_.load(std::memory_order_relaxed) && records.size() == row_records_ &&
           ring_.try_push_all(records);
  }
  /// As push(), but a full ring or a closed log is not counted as a drop: the caller tries again
  /// (the simulated clock's back-pressure) or gives up with push(). Real-time safe.
  bool try_push(const SampleRecord& record) noexcept { return try_push_row({&record, 1}); }
  /// True once close() has begun: nothing pushed from then on reaches the file.
  bool closed() const noexcept { return closed_.load(std::memory_order_relaxed); }

  /// Stops the writer thread after it has written everything pushed before the call, flushes
  /// and syncs the file. Call after the loop has stopped pushing. Idempotent.
  SampleLogCounts close();

  /// Live counts (any thread).
  std::uint64_t written() const noexcept { return written_.load(std::memory_order_relaxed); }
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  const std::filesystem::path& path() const noexcept { return path_; }
  /// Records per row: the stage's axes, 1 for one axis.
  std::size_t row_records() const noexcept { return row_records_; }

 private:
  void run();
  void drain_and_format();
  void write_out();

  SampleLogOptions options_;
  std::filesystem::path path_;
  std::size_t row_records_ = 1;
  int fd_ = -1;
  SpscRing<SampleRecord> ring_;
  std::atomic<bool> closed_{false};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> dropped_{0};

  // Writer-thread state.
  std::string out_;
  std::uint64_t rows_in_out_ = 0;
  std::string error_;

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::mutex close_mutex_;
  SampleLogCounts final_counts_;
  std::thread thread_;
};

/// Column names of the CSV, in file order.
std::span<const std::string_view> sample_log_columns() noexcept;
/// Whether `id` may name a sample log (SampleLogOptions::run_id's rule): 1-128 characters of
/// [A-Za-z0-9._-], not starting with '.', not "latest".
bool valid_sample_log_id(std::string_view id) noexcept;
/// Column names of a stage's CSV with these axes (empty: sample_log_columns()).
std::vector<std::string> sample_log_columns(std::span<const std::string> axes);

/// Reads the '#' lines at the head of a sample log and merges their JSON objects.
/// Throws std::runtime_error naming the file and line for a comment that is not a JSON object.
nlohmann::json read_sample_log_header(const std::filesystem::path& path);

}  // namespace hystbench::daemon
