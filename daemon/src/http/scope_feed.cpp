#include "hystbench/daemon/http/scope_feed.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace hystbench::daemon {

namespace {

// A scope shows 0.1 nm and 0.1 mV at best: rounded, a sample is a few characters of JSON.
double for_display(double v) { return std::isfinite(v) ? std::round(v * 1e4) / 1e4 : v; }

ScopeFeedOptions checked(ScopeFeedOptions o) {
  if (!(o.loop_rate_hz > 0.0) || !(o.history_s > 0.0) || !(o.backlog_s >= 0.0) ||
      o.backlog_s > o.history_s || o.axes.empty() || o.axes.size() > drivers::kMaxAxes ||
      o.max_frame_samples == 0 || o.poll_interval.count() <= 0) {
    throw std::invalid_argument(
        "scope feed: loop_rate_hz and history_s > 0, 0 <= backlog_s <= history_s, 1-6 axes, "
        "max_frame_samples and poll_interval > 0");
  }
  return o;
}

}  // namespace

ScopeFeed::ScopeFeed(ScopeTap& tap, ScopeFeedOptions options)
    : tap_(tap),
      options_(checked(std::move(options))),
      dt_s_(tap.decimation() / options_.loop_rate_hz),
      capacity_(std::max<std::size_t>(
          2, static_cast<std::size_t>(std::ceil(options_.history_s / dt_s_)))),
      backlog_(static_cast<std::size_t>(std::ceil(options_.backlog_s / dt_s_))),
      drained_(1024),
      history_(capacity_) {}

ScopeFeed::~ScopeFeed() { stop(); }

void ScopeFeed::start() {
  if (thread_.joinable()) return;
  stop_.store(false, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
}

void ScopeFeed::stop() {
  {
    std::lock_guard lock(mutex_);
    stop_.store(true, std::memory_order_release);
  }
  arrived_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ScopeFeed::run() {
  while (!stop_.load(std::memory_order_acquire)) {
    drain();
    std::this_thread::sleep_for(options_.poll_interval);
  }
}

void ScopeFeed::drain() {
  bool any = false;
  for (;;) {
    const std::size_t n = tap_.drain(drained_);
    if (n == 0) break;
    std::lock_guard lock(mutex_);
    if (next_ == 0) origin_ns_ = drained_[0].time_ns;
    for (std::size_t i = 0; i < n; ++i) history_[(next_ + i) % capacity_] = drained_[i];
    next_ += n;
    any = true;
  }
  if (any) arrived_.notify_all();
}

std::uint64_t ScopeFeed::newest() const {
  std::lock_guard lock(mutex_);
  return next_;
}

std::uint64_t ScopeFeed::start_cursor() const {
  std::lock_guard lock(mutex_);
  const std::uint64_t kept = std::min<std::uint64_t>(next_, capacity_);
  return next_ - std::min<std::uint64_t>(kept, backlog_);
}

std::string ScopeFeed::frame_after(std::uint64_t& cursor, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  arrived_.wait_for(lock, timeout, [&] { return next_ > cursor || stopped(); });
  if (stopped() || next_ <= cursor) return {};
  if (next_ - cursor > capacity_) {  // fell behind the history: start again near the newest
    const std::uint64_t kept = std::min<std::uint64_t>(next_, capacity_);
    cursor = next_ - std::min<std::uint64_t>(kept, backlog_);
  }
  const std::uint64_t to = std::min<std::uint64_t>(next_, cursor + options_.max_frame_samples);
  std::string text = frame(cursor, to);
  cursor = to;
  return text;
}

std::string ScopeFeed::frame(std::uint64_t from, std::uint64_t to) const {
  using nlohmann::json;
  const std::size_t axes =
      std::min<std::size_t>(options_.axes.size(), history_[from % capacity_].axes);
  json y = json::array(), yr = json::array(), u = json::array();
  bool running = false;
  for (std::size_t a = 0; a < axes; ++a) {
    json ya = json::array(), yra = json::array(), ua = json::array();
    for (std::uint64_t n = from; n < to; ++n) {
      const ScopeSample& s = history_[n % capacity_];
      ya.push_back(for_display(s.y[a]));  // NaN and infinities are written as null
      yra.push_back(for_display(s.yr[a]));
      ua.push_back(for_display(s.u[a]));
      running = running || s.running;
    }
    y.push_back(std::move(ya));
    yr.push_back(std::move(yra));
    u.push_back(std::move(ua));
  }
  const ScopeSample& first = history_[from % capacity_];
  const json frame = {{"seq", from},
                      {"t0", 1e-9 * static_cast<double>(first.time_ns - origin_ns_)},
                      {"dt", dt_s_},
                      {"running", running},
                      {"axes", options_.axes},
                      {"y", std::move(y)},
                      {"yr", std::move(yr)},
                      {"u", std::move(u)},
                      {"dropped", tap_.dropped()}};
  return frame.dump();
}

}  // namespace hystbench::daemon
