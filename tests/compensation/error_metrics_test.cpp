#include "hystbench/compensation/error_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace hc = hystbench::compensation;

TEST(PercentOfRange, IsTheValueAsAShareOfTheSpanAndZeroWithoutOne) {
  EXPECT_DOUBLE_EQ(hc::percent_of_range(0.45, 45.0), 1.0);
  EXPECT_DOUBLE_EQ(hc::percent_of_range(-0.9, 45.0), -2.0);
  // A run that did not move has no span: its share is 0, never a division by zero.
  EXPECT_EQ(hc::percent_of_range(0.3, 0.0), 0.0);
  EXPECT_EQ(hc::percent_of_range(0.3, -1.0), 0.0);
}

TEST(ErrorStats, MeasuresTheErrorOverTheMeasuredSpanAndReportsItsShares) {
  const std::vector<double> measured = {0.0, 10.0, 20.0, 10.0};
  const std::vector<double> predicted = {1.0, 10.0, 19.0, 10.0, 99.0};  // the extra one unread
  const hc::ErrorStats s = hc::error_stats(measured, predicted);
  EXPECT_EQ(s.samples, 4u);
  EXPECT_DOUBLE_EQ(s.range, 20.0);
  EXPECT_DOUBLE_EQ(s.max_abs, 1.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(s.rmse_percent(), 100.0 * std::sqrt(0.5) / 20.0);
  EXPECT_DOUBLE_EQ(s.max_percent(), 5.0);
  const nlohmann::json j = hc::to_json(s);
  EXPECT_DOUBLE_EQ(j.at("max_percent").get<double>(), 5.0);
  EXPECT_EQ(j.at("samples").get<std::size_t>(), 4u);
}

TEST(ErrorStats, AFlatMeasurementHasNoShare) {
  const std::vector<double> flat = {3.0, 3.0, 3.0};
  const std::vector<double> predicted = {2.0, 3.0, 4.0};
  const hc::ErrorStats s = hc::error_stats(flat, predicted);
  EXPECT_DOUBLE_EQ(s.range, 0.0);
  EXPECT_DOUBLE_EQ(s.max_abs, 1.0);
  EXPECT_EQ(s.rmse_percent(), 0.0);
  EXPECT_EQ(s.max_percent(), 0.0);
  EXPECT_EQ(hc::error_stats({}, predicted).samples, 0u);
}
