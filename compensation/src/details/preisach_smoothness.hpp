#pragma once
// The Preisach fit's smoothness penalty (identification internals): the sum of squared
// differences between neighbouring cells' densities (the next alpha row, the next beta column),
// added to a least-squares Gram matrix over the cells' unknowns.
#include <Eigen/Dense>
#include <cstddef>

namespace hystbench::compensation::details {

/// Adds weight x scale x D to g's cells block (the n (n + 1) / 2 unknowns from `first` on, in
/// PreisachModel::cell_index order), where scale is that block's mean diagonal in g (the columns'
/// mean square: a weight independent of units and record length) and D the penalty's Gram.
void add_preisach_smoothness(Eigen::MatrixXd& g, std::size_t n, Eigen::Index first, double weight);

}  // namespace hystbench::compensation::details
