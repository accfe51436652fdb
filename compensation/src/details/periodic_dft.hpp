#pragma once
// The DFT of periodic records averaged over their periods (mimo_identification internals).
// Allocates; not real-time safe.
#include <Eigen/Dense>
#include <cstddef>
#include <vector>

namespace hystbench::compensation::details {

// The mean over periods [from, np) of the DFT of x (channels x (np n)) at `bins`.
Eigen::MatrixXcd averaged_dft(const Eigen::MatrixXd& x, std::size_t n, std::size_t np,
                              std::size_t from, const std::vector<std::size_t>& bins);

}  // namespace hystbench::compensation::details
