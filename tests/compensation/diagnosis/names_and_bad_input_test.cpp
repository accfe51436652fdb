// Diagnosis: the causes' names, and records the diagnosis refuses with a clear message.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"

namespace hc = hystbench::compensation;

TEST(Diagnosis, CauseNamesRoundTrip) {
  EXPECT_EQ(hc::to_string(hc::Cause::kNone), "none");
  for (const hc::Cause c : hc::candidate_causes()) {
    EXPECT_EQ(hc::cause_from_string(hc::to_string(c)), c);
  }
  EXPECT_EQ(hc::candidate_causes().size(), 7u);
  EXPECT_EQ(hc::cause_from_string("rate_dependence"), hc::Cause::kRateDependence);
  EXPECT_EQ(hc::cause_from_string("loop_shape"), hc::Cause::kLoopShape);
  EXPECT_FALSE(hc::cause_from_string("resonance").has_value());
}

TEST(Diagnosis, RejectsBadRecordsWithAClearMessage) {
  auto message = [](const std::vector<double>& t, const std::vector<double>& u,
                    const std::vector<double>& y) -> std::string {
    try {
      hc::diagnose(t, u, y);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  };
  std::vector<double> t(1000), u(1000), y(1000);
  for (std::size_t k = 0; k < t.size(); ++k) {
    t[k] = 1e-3 * static_cast<double>(k);
    u[k] = 50.0 + 40.0 * std::sin(0.02 * static_cast<double>(k));
    y[k] = 0.3 * u[k];
  }
  EXPECT_NE(message({t.begin(), t.begin() + 100}, {u.begin(), u.begin() + 100},
                    {y.begin(), y.begin() + 100})
                .find("too few samples"),
            std::string::npos);
  EXPECT_NE(message(t, std::vector<double>(1000, 3.0), y).find("input u is constant"),
            std::string::npos);
  auto bad = y;
  bad[17] = std::nan("");
  EXPECT_NE(message(t, u, bad).find("y[17] is not a finite number"), std::string::npos);
  EXPECT_NE(message(t, u, std::vector<double>(999, 1.0)).find("same length"), std::string::npos);
  EXPECT_NE(message(t, u, std::vector<double>(1000, 2.0)).find("output y is constant"),
            std::string::npos);
  auto back = t;
  back[500] = back[499];
  EXPECT_NE(message(back, u, y).find("strictly increasing"), std::string::npos);
}
