#pragma once
// The rate-dependent paper's identification (section III-B, eq. 15-17) on a single record:
// the record is cut into half-cycles between input reversals, the half-cycles are grouped by
// their mean |du/dt|, the cumulative play weights are fitted per group (dead zones shared, from
// a rate-independent MPI fit), and each cumulative weight is regressed on rate by weighted least
// squares, W_i(rate) = W^_i + c_i rate, with W^_i >= eps and c_i >= 0 (the loop widens with rate).
#include <Eigen/Dense>
#include <optional>
#include <span>

#include "details/designs.hpp"

namespace hystbench::compensation::details {

/// Spread of the mean |du/dt| of the half-cycles (between input reversals) on [begin, end):
/// the ratio of the 90th to the 10th percentile (1 when there are fewer than 4 half-cycles).
/// Rate dependence is separable from input level only when the same levels are crossed at
/// different rates, i.e. when this is clearly above 1.
double half_cycle_rate_spread(std::span<const double> u, double dt, std::size_t begin,
                              std::size_t end);

/// Unknowns of Design(s) (s.kind must be kRateDependentPi, without creep) with the inverse
/// dead-zone cumulative weights held at `dead_zone_cumulative` (Design::dead_zone_unknowns()
/// values), fitted on rows [begin, end). std::nullopt when the half-cycles do not cover at
/// least two distinct rate groups (a single-rate record cannot show rate dependence).
std::optional<Eigen::VectorXd> fit_rate_groups(const ModelStructure& s,
                                               const Eigen::VectorXd& dead_zone_cumulative,
                                               std::span<const double> u, std::span<const double> y,
                                               std::size_t begin, std::size_t end);

}  // namespace hystbench::compensation::details
