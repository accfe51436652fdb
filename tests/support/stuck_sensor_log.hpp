#pragma once
// Test helper: where a run's log shows a frozen reading (the trailing run of identical y), the
// tick at which the output u was `span_v` away from its value then, and how many ticks after
// that the run ended (its last row is the faulted tick).
#include <cmath>
#include <cstddef>

#include "hystbench/cli/offline/data_table.hpp"

namespace hystbench::test {

struct FrozenReading {
  std::size_t frozen = 0;  ///< row where the reading took its final value
  std::size_t moved = 0;   ///< first row at least span_v away from u[frozen] (rows if none)
  std::size_t rows = 0;    ///< rows in the log
  bool output_moved() const { return moved < rows; }
  std::size_t fault_after_moved() const { return rows - 1 - moved; }
};

inline FrozenReading find_frozen_reading(const cli::DataTable& log, double span_v) {
  const auto& y = log.column("y");
  const auto& u = log.column("u");
  FrozenReading f;
  f.rows = y.size();
  if (f.rows == 0) return f;
  std::size_t same = 1;
  while (same < y.size() && y[y.size() - 1 - same] == y.back()) ++same;
  f.frozen = y.size() - same;
  f.moved = f.frozen;
  while (f.moved < u.size() && std::abs(u[f.moved] - u[f.frozen]) < span_v) ++f.moved;
  return f;
}

}  // namespace hystbench::test
