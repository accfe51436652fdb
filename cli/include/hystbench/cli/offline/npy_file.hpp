#pragma once
// NumPy .npy files (format 1.0 or 2.0): a little-endian float64 ('<f8') or float32 ('<f4') array
// in C order, read as its shape and its values as doubles. Units: none (the file's own).
// Not real-time safe.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace hystbench::cli {

struct NpyArray {
  std::vector<std::size_t> shape;  ///< empty for a 0-d array (one value)
  std::vector<double> values;      ///< C order: the last index varies fastest
};

/// Reads path's array. Throws DataFileError naming the file and the cause: cannot open, not a
/// .npy (no magic), an unsupported format version, a bad header, an unsupported dtype, Fortran
/// order, truncated data (expected and actual byte counts) or bytes after the data.
NpyArray read_npy(const std::string& path);

/// A shape as NumPy prints it: "(8192, 3, 6, 2)", "(5,)", "()".
std::string shape_text(std::span<const std::size_t> shape);

}  // namespace hystbench::cli
