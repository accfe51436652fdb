#include "runs/details/diagnosis_ahead.hpp"

#include <algorithm>
#include <utility>

namespace hystbench::daemon::details {

DiagnosisAhead::DiagnosisAhead(Task task, std::vector<std::size_t> order)
    : task_(std::move(task)), order_(std::move(order)), worker_([this] { run(); }) {}

DiagnosisAhead::~DiagnosisAhead() { stop_and_join(); }

void DiagnosisAhead::stop_and_join() {
  {
    std::lock_guard lock(mutex_);
    cancel_ = true;
  }
  if (worker_.joinable()) worker_.join();
}

void DiagnosisAhead::run() {
  for (const std::size_t i : order_) {
    {
      std::lock_guard lock(mutex_);
      if (cancel_ || stop_after_running_) break;
      running_ = i;
    }
    const Progress cancellable = [this](double, const std::string&) {
      std::lock_guard lock(mutex_);
      if (cancel_) throw Cancelled{};
    };
    try {
      compensation::Diagnosis d = task_(i, cancellable);
      std::lock_guard lock(mutex_);
      done_.emplace(i, std::move(d));
    } catch (const Cancelled&) {
      break;  // running_ is reset below
    } catch (...) {
      std::lock_guard lock(mutex_);
      failed_.emplace(i, std::current_exception());
    }
    {
      std::lock_guard lock(mutex_);
      running_.reset();
    }
    changed_.notify_all();
  }
  std::lock_guard lock(mutex_);
  running_.reset();
  changed_.notify_all();
}

DiagnosisAhead::Taken DiagnosisAhead::take(std::size_t candidate, const Progress& progress) {
  std::string how = "during the verification";
  {
    std::unique_lock lock(mutex_);
    if (!done_.contains(candidate) && !failed_.contains(candidate) && running_ == candidate) {
      stop_after_running_ = true;
      how = "partly during the verification";
      changed_.wait(lock, [&] { return running_ != candidate; });
    }
  }
  stop_and_join();
  if (const auto f = failed_.find(candidate); f != failed_.end()) std::rethrow_exception(f->second);
  if (auto d = done_.find(candidate); d != done_.end()) return {std::move(d->second), how};
  return {task_(candidate, progress), "after the verification"};
}

}  // namespace hystbench::daemon::details
