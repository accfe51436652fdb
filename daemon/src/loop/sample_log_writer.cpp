#include "hystbench/daemon/loop/sample_log_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <ctime>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "hystbench/daemon/loop/realtime.hpp"
#include "hystbench/sim/simulated_stage_config.hpp"
#include "loop/details/posix_io.hpp"
#include "loop/details/utc_clock.hpp"

namespace hystbench::daemon {

namespace {

constexpr std::array<std::string_view, 12> kColumns = {
    "index", "t", "t_scheduled_ns", "t_wake_ns", "exec_ns", "yr", "u_ff", "u_fb",
    "u",     "y", "y_model",        "flags"};
constexpr std::array<std::string_view, 12> kUnits = {"1", "s", "ns", "ns", "ns", "um",
                                                     "V", "V", "V",  "um", "um", "1"};
/// A stage's columns per axis (the one-axis columns from yr on, suffixed with the axis' name).
constexpr std::size_t kFirstAxisColumn = 5;
constexpr std::size_t kBatch = 1024;
constexpr std::size_t kWriteThreshold = std::size_t{256} << 10;
constexpr std::size_t kMaxRowChars = std::size_t{12} * 32;

std::string comment_line(const nlohmann::json& object) {
  return "# " + object.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

/// Each column's name and unit, for these axes.
std::vector<std::pair<std::string, std::string_view>> columns_with_units(
    std::span<const std::string> axes) {
  std::vector<std::pair<std::string, std::string_view>> out;
  const std::size_t per_axis_end = axes.empty() ? kColumns.size() : kFirstAxisColumn;
  for (std::size_t i = 0; i < per_axis_end; ++i) out.emplace_back(kColumns[i], kUnits[i]);
  for (const std::string& axis : axes) {
    for (std::size_t i = kFirstAxisColumn; i < kColumns.size(); ++i) {
      out.emplace_back(std::string(kColumns[i]) + "_" + axis, kUnits[i]);
    }
  }
  return out;
}

std::string make_header(const SampleLogOptions& o) {
  std::string h = comment_line({{"schema", kSampleLogSchema},
                                {"run_id", o.run_id},
                                {"created", details::utc_now_iso8601()}});
  for (const auto& [key, value] : o.header.items()) h += comment_line({{key, value}});
  const auto columns_units = columns_with_units(o.axes);
  nlohmann::json units = nlohmann::json::object();
  for (const auto& [name, unit] : columns_units) units[name] = unit;
  h += comment_line({{"units", units}});
  h += comment_line({{"flags",
                      {{"output_clamped", kSampleOutputClamped},
                       {"slew_limited", kSampleSlewLimited},
                       {"reference_limited", kSampleReferenceLimited},
                       {"feedback_saturated", kSampleFeedbackSaturated},
                       {"overrun", kSampleOverrun},
                       {"fault", kSampleFault},
                       {"stale", kSampleStale},
                       {"open_loop", kSampleOpenLoop}}}});
  nlohmann::json columns = nlohmann::json::array();
  for (const auto& column : columns_units) columns.push_back(column.first);
  h += comment_line({{"columns", columns}});
  for (std::size_t i = 0; i < columns_units.size(); ++i) {
    h += (i ? "," : "");
    h += columns_units[i].first;
  }
  h += "\n";
  return h;
}

SampleLogOptions validated(SampleLogOptions o) {
  if (!valid_sample_log_id(o.run_id)) {
    throw std::invalid_argument("sample log: run id '" + o.run_id +
                                "' must be 1-128 characters of [A-Za-z0-9._-], not starting "
                                "with '.', and not 'latest'");
  }
  if (o.log_dir.empty()) throw std::invalid_argument("sample log: log_dir is empty");
  if (!o.header.is_object()) throw std::invalid_argument("sample log: header must be an object");
  for (const char* reserved : {"schema", "run_id", "created", "units", "flags", "columns"}) {
    if (o.header.contains(reserved)) {
      throw std::invalid_argument(std::string("sample log: header key '") + reserved +
                                  "' is reserved");
    }
  }
  if (!o.axes.empty()) {
    if (o.axes.size() < 2 || o.axes.size() > 6) {
      throw std::invalid_argument("sample log: a stage has 2 to 6 axes, not " +
                                  std::to_string(o.axes.size()));
    }
    for (std::size_t i = 0; i < o.axes.size(); ++i) {
      if (!sim::is_axis_name(o.axes[i])) {
        throw std::invalid_argument("sample log: axis name '" + o.axes[i] +
                                    "' must be 1-16 characters of [a-z0-9_]");
      }
      if (std::find(o.axes.begin(), o.axes.begin() + static_cast<std::ptrdiff_t>(i), o.axes[i]) !=
          o.axes.begin() + static_cast<std::ptrdiff_t>(i)) {
        throw std::invalid_argument("sample log: axis name '" + o.axes[i] + "' is given twice");
      }
    }
  }
  if (o.poll_interval.count() <= 0 || o.flush_interval.count() <= 0) {
    throw std::invalid_argument("sample log: poll and flush intervals must be > 0");
  }
  return o;
}

char* put(char* p, std::string_view s) {
  for (const char c : s) *p++ = c;
  return p;
}

char* put_int(char* p, std::int64_t v) { return std::to_chars(p, p + 24, v).ptr; }
char* put_uint(char* p, std::uint64_t v) { return std::to_chars(p, p + 24, v).ptr; }

// Shortest representation that reads back to the same double; NaN/Inf spelled the way pandas,
// MATLAB and strtod all accept.
char* put_double(char* p, double v) {
  if (std::isnan(v)) return put(p, "NaN");
  if (std::isinf(v)) return put(p, v > 0 ? "Inf" : "-Inf");
  return std::to_chars(p, p + 32, v).ptr;
}

/// One row: the first record's times, then each record's values (one per axis).
char* format_row(char* p, std::span<const SampleRecord> row) {
  const SampleRecord& first = row.front();
  p = put_uint(p, first.index);
  *p++ = ',';
  p = put_double(p, static_cast<double>(first.scheduled_ns) / 1e9);
  *p++ = ',';
  p = put_int(p, first.scheduled_ns);
  *p++ = ',';
  p = put_int(p, first.wake_ns);
  *p++ = ',';
  p = put_int(p, first.exec_ns);
  for (const SampleRecord& r : row) {
    for (const double v : {r.reference, r.u_ff, r.u_fb, r.u_out, r.y_measured, r.y_model}) {
      *p++ = ',';
      p = put_double(p, v);
    }
    *p++ = ',';
    p = put_uint(p, r.flags);
  }
  *p++ = '\n';
  return p;
}

}  // namespace

bool valid_sample_log_id(std::string_view id) noexcept {
  if (id.empty() || id.size() > 128 || id.front() == '.' || id == "latest") return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  });
}

std::span<const std::string_view> sample_log_columns() noexcept { return kColumns; }

std::vector<std::string> sample_log_columns(std::span<const std::string> axes) {
  std::vector<std::string> out;
  for (auto& column : columns_with_units(axes)) out.push_back(std::move(column.first));
  return out;
}

SampleLogWriter::SampleLogWriter(SampleLogOptions options)
    : options_(validated(std::move(options))),
      row_records_(std::max<std::size_t>(1, options_.axes.size())),
      ring_(options_.ring_capacity * row_records_) {
  std::error_code ec;
  std::filesystem::create_directories(options_.log_dir, ec);
  if (ec) throw std::system_error(ec, "sample log: cannot create " + options_.log_dir.string());
  path_ = options_.log_dir / (options_.run_id + ".csv");
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw std::system_error(errno, std::generic_category(),
                            "sample log: cannot create " + path_.string());
  }
  const std::string header = make_header(options_);
  if (!details::write_all(fd_, header.data(), header.size())) {
    const int err = errno;
    ::close(fd_);
    throw std::system_error(err, std::generic_category(),
                            "sample log: cannot write " + path_.string());
  }
  if (options_.update_latest_link) {
    try {
      details::replace_symlink(options_.log_dir / "latest.csv", path_.filename());
    } catch (...) {
      ::close(fd_);
      throw;
    }
  }
  try {
    out_.reserve(kWriteThreshold + kBatch * kMaxRowChars);
    thread_ = std::thread([this] { run(); });
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

SampleLogWriter::~SampleLogWriter() { close(); }

bool SampleLogWriter::push_row(std::span<const SampleRecord> records) noexcept {
  if (try_push_row(records)) return true;
  dropped_.fetch_add(1, std::memory_order_relaxed);  // rare path: an atomic add is fine
  return false;
}

void SampleLogWriter::run() {
  set_normal_scheduling();
  auto last_flush = std::chrono::steady_clock::now();
  std::unique_lock lock(mutex_);
  for (;;) {
    const bool stopping = wake_.wait_for(lock, options_.poll_interval, [this] { return stop_; });
    lock.unlock();
    drain_and_format();
    const auto now = std::chrono::steady_clock::now();
    if (stopping || now - last_flush >= options_.flush_interval) {
      write_out();
      last_flush = now;
    }
    if (stopping) break;
    lock.lock();
  }
  if (error_.empty() && ::fdatasync(fd_) != 0) error_ = details::errno_message("fdatasync");
}

void SampleLogWriter::drain_and_format() {
  std::array<SampleRecord, kBatch> batch;
  // Whole rows only: the loop pushes a row's records at once, so the ring holds whole rows.
  const std::size_t per_row = row_records_;
  const std::span<SampleRecord> rows(batch.data(), kBatch / per_row * per_row);
  for (;;) {
    const std::size_t n = ring_.pop_batch(rows) / per_row;
    if (n == 0) return;
    const std::size_t old = out_.size();
    out_.resize(old + n * kMaxRowChars * per_row);
    char* p = out_.data() + old;
    for (std::size_t i = 0; i < n; ++i) {
      p = format_row(p, std::span<const SampleRecord>(batch.data() + i * per_row, per_row));
    }
    out_.resize(static_cast<std::size_t>(p - out_.data()));
    rows_in_out_ += n;
    if (out_.size() >= kWriteThreshold) write_out();
  }
}

void SampleLogWriter::write_out() {
  if (rows_in_out_ == 0) return;
  if (error_.empty() && !details::write_all(fd_, out_.data(), out_.size())) {
    error_ = details::errno_message("write " + path_.string());
  }
  auto& counter = error_.empty() ? written_ : dropped_;
  counter.fetch_add(rows_in_out_, std::memory_order_relaxed);
  out_.clear();
  rows_in_out_ = 0;
}

SampleLogCounts SampleLogWriter::close() {
  std::lock_guard close_lock(close_mutex_);
  if (!thread_.joinable()) return final_counts_;
  closed_.store(true, std::memory_order_relaxed);
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  // Whatever raced into the ring after the last drain never reaches the file.
  SampleRecord leftover;
  std::uint64_t left_records = 0;
  while (ring_.try_pop(leftover)) ++left_records;
  dropped_.fetch_add(left_records / row_records_, std::memory_order_relaxed);
  if (::close(fd_) != 0 && error_.empty()) error_ = details::errno_message("close");
  fd_ = -1;
  final_counts_ = {written(), dropped(), error_};
  return final_counts_;
}

nlohmann::json read_sample_log_header(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  nlohmann::json header = nlohmann::json::object();
  std::string line;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] != '#') break;
    nlohmann::json part = nlohmann::json::parse(line.substr(1), nullptr, false);
    if (!part.is_object()) {
      throw std::runtime_error(path.string() + ":" + std::to_string(line_no) +
                               ": comment is not a JSON object");
    }
    header.update(part);
  }
  return header;
}

}  // namespace hystbench::daemon
