#pragma once
// The offline commands' progress on stderr: one line, rewritten in place ("[ 42 %] what").
#include <iomanip>
#include <ostream>
#include <string>

namespace hystbench::cli::details {

inline void progress_line(std::ostream& err, double fraction, const std::string& what) {
  err << "\r[" << std::setw(3) << static_cast<int>(100.0 * fraction) << " %] " << what << "\x1b[K"
      << std::flush;
}

}  // namespace hystbench::cli::details
