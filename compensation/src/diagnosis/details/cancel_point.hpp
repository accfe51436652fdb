#pragma once
// Cancellation inside a diagnosis (internals): DiagnosisOptions::cancelled, polled where the fits
// start (cancellation_point()) without passing it through every fit's signature. A CancelScope
// makes it the polled one on its thread for its lifetime (the diagnosis's thread, and each thread
// the candidates run on); without a scope the point does nothing. Not for the real-time path.
#include <functional>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

namespace cancel_detail {
inline thread_local const std::function<bool()>* polled = nullptr;
}  // namespace cancel_detail

class CancelScope {
 public:
  explicit CancelScope(const DiagnosisOptions& options) : previous_(cancel_detail::polled) {
    if (options.cancelled) cancel_detail::polled = &options.cancelled;
  }
  ~CancelScope() { cancel_detail::polled = previous_; }
  CancelScope(const CancelScope&) = delete;
  CancelScope& operator=(const CancelScope&) = delete;

 private:
  const std::function<bool()>* previous_;
};

/// Throws DiagnosisCancelled when the scope's DiagnosisOptions::cancelled says so.
inline void cancellation_point() {
  const std::function<bool()>* c = cancel_detail::polled;
  if (c != nullptr && (*c)()) throw DiagnosisCancelled();
}

}  // namespace hystbench::compensation::details::diagnosis
