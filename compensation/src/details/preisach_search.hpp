#pragma once
// The Preisach plane's output map and smoothness chosen on held-out data (identification
// internals), over details::Design: each output map (m one-sided dead zones per side, uniform
// over the scored output's range about its middle; 0 = the identity) with each smoothness weight
// is fitted on [begin, split), simulated from sample 0 and scored on [split, end); the best is
// then fitted on [begin, end). The base structure's creep lags and drift column are fitted with
// the cells (scored with the drift added). Not real-time.
#include <Eigen/Dense>
#include <span>
#include <vector>

#include "details/designs.hpp"

namespace hystbench::compensation::details {

struct PreisachSearch {
  ModelStructure structure;       ///< the base with the kept output map and smoothness
  Eigen::VectorXd x;              ///< its unknowns, fitted on [begin, end)
  double heldout_rms = 0.0;       ///< of its fit on [begin, split), on [split, end)
  std::vector<double> tried_rms;  ///< held-out rms of each smoothness weight (the kept map's)
};

/// base: kind Preisach with its cells and plane range (its dead zones and smoothness are
/// replaced). Requires begin < split < end <= u.size() == y.size().
PreisachSearch search_preisach(const ModelStructure& base, std::span<const double> u,
                               std::span<const double> y, std::size_t begin, std::size_t split,
                               std::size_t end, std::span<const double> smoothness,
                               std::span<const std::size_t> output_zones);

}  // namespace hystbench::compensation::details
