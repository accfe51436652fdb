#pragma once
// Independent tasks run on the machine's cores: run_parallel(n, task, threads) calls
// task(0..n-1), each once, on up to `threads` threads (0: hardware_concurrency; the calling thread
// one of them; all in it where there is one thread or one task), and returns when all have ended.
// Once a task has thrown, no further one starts; the first exception is rethrown then. Not for the
// real-time path (it starts threads).
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace hystbench::compensation::details {

inline void run_parallel(std::size_t n, const std::function<void(std::size_t)>& task,
                         std::size_t threads = 0) {
  const std::size_t cores = std::max(1U, std::thread::hardware_concurrency());
  const std::size_t workers = std::min(n, threads == 0 ? cores : threads);
  if (workers <= 1) {
    for (std::size_t i = 0; i < n; ++i) task(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto work = [&] {
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        task(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;  // no further task starts
      }
    }
  };
  std::vector<std::thread> helpers;
  helpers.reserve(workers - 1);
  for (std::size_t k = 1; k < workers; ++k) helpers.emplace_back(work);
  work();
  for (auto& t : helpers) t.join();
  if (error) std::rethrow_exception(error);
}

/// Progress of n tasks run at once: each reports its own fraction; the sum reaches `report` as
/// one fraction in [0, 1] (serialised, so `report` need not be thread-safe).
class SharedProgress {
 public:
  SharedProgress(std::size_t n, std::function<void(double, const std::string&)> report)
      : done_(n, 0.0), report_(std::move(report)) {}
  void operator()(std::size_t task, double fraction, const std::string& what) {
    if (!report_) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    done_[task] = fraction;
    double sum = 0.0;
    for (const double d : done_) sum += d;
    report_(sum / static_cast<double>(done_.size()), what);
  }

 private:
  std::vector<double> done_;
  std::function<void(double, const std::string&)> report_;
  std::mutex mutex_;
};

}  // namespace hystbench::compensation::details
