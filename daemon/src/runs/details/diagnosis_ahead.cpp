#include "runs/details/diagnosis_ahead.hpp"

#include <algorithm>
#include <utility>

namespace hystbench::daemon::details {

DiagnosisAhead::DiagnosisAhead(Task task, std::vector<std::size_t> order)
    : task_(std::make_shared<const Task>(std::move(task))),
      queue_(order.begin(), order.end()),
      worker_([this] { run(); }) {}

DiagnosisAhead::~DiagnosisAhead() { stop_and_join(); }

void DiagnosisAhead::cancel() {
  {
    std::lock_guard lock(mutex_);
    cancel_ = true;
  }
  changed_.notify_all();  // a worker waiting for more
}

void DiagnosisAhead::stop_and_join() {
  cancel();
  if (worker_.joinable()) worker_.join();
}

void DiagnosisAhead::queue_more(Task task, const std::vector<std::size_t>& order) {
  {
    std::lock_guard lock(mutex_);
    if (focused_ || cancel_ || stop_after_running_) return;
    task_ = std::make_shared<const Task>(std::move(task));
    for (const std::size_t i : order) {
      const bool known = done_.contains(i) || failed_.contains(i) || running_ == i ||
                         std::find(queue_.begin(), queue_.end(), i) != queue_.end();
      if (!known) queue_.push_back(i);
    }
  }
  changed_.notify_all();
}

void DiagnosisAhead::focus(std::size_t candidate) {
  {
    std::lock_guard lock(mutex_);
    focused_ = true;
    queue_.clear();
    if (done_.contains(candidate) || failed_.contains(candidate) || running_ == candidate) return;
    queue_.push_back(candidate);
    abandon_ = running_.has_value();
  }
  changed_.notify_all();
}

bool DiagnosisAhead::ready(std::size_t candidate) {
  std::lock_guard lock(mutex_);
  return done_.contains(candidate) || failed_.contains(candidate);
}

void DiagnosisAhead::run() {
  for (;;) {
    std::size_t i = 0;
    std::shared_ptr<const Task> task;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return cancel_ || stop_after_running_ || !queue_.empty(); });
      if (cancel_ || stop_after_running_) break;
      i = queue_.front();
      queue_.pop_front();
      running_ = i;
      abandon_ = false;
      task = task_;
    }
    const auto stopped = [this] {
      std::lock_guard lock(mutex_);
      return cancel_ || abandon_;
    };
    const Controls controls{[stopped](double, const std::string&) {
                              if (stopped()) throw Cancelled{};
                            },
                            stopped, 1};
    try {
      compensation::Diagnosis d = (*task)(i, controls);
      std::lock_guard lock(mutex_);
      done_.emplace(i, std::move(d));
    } catch (const Cancelled&) {
      // Abandoned for the one focused on (next in the queue), or cancelled: the loop stops.
    } catch (const compensation::DiagnosisCancelled&) {
      // The same, inside a fit.
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
  bool ahead = false;
  {
    std::unique_lock lock(mutex_);
    if (!done_.contains(candidate) && !failed_.contains(candidate) && running_ == candidate) {
      stop_after_running_ = true;
      how = "partly during the verification";
      changed_.wait(lock, [&] { return running_ != candidate; });
    }
    ahead = done_.contains(candidate) || failed_.contains(candidate);
  }
  if (!ahead) {
    // Not started: the worker, busy with one abandoned or idle, stops at its next fit while the
    // diagnosis runs here.
    cancel();
    Taken taken{(*task_)(candidate, Controls{progress, nullptr, 0}), "after the verification"};
    stop_and_join();
    return taken;
  }
  stop_and_join();
  if (const auto f = failed_.find(candidate); f != failed_.end()) std::rethrow_exception(f->second);
  return {std::move(done_.at(candidate)), how};
}

}  // namespace hystbench::daemon::details
