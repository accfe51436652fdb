// details::ScopedNoDenormals flushes subnormal results to zero while it lives and gives the
// thread its previous mode back when it ends.
#include "details/scoped_no_denormals.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hd = hystbench::compensation::details;

namespace {

// A product whose exact result is subnormal; volatile so the compiler cannot fold it.
double subnormal_product() {
  volatile double tiny = std::numeric_limits<double>::min();  // smallest normal
  volatile double half = 0.5;
  return tiny * half;
}

}  // namespace

TEST(ScopedNoDenormals, FlushesASubnormalProductToZeroAndRestores) {
#if !defined(__SSE2__)
  GTEST_SKIP() << "the flush is built for SSE2 targets only; elsewhere the guard does nothing";
#else
  ASSERT_EQ(std::fpclassify(subnormal_product()), FP_SUBNORMAL) << "the default mode keeps them";
  {
    const hd::ScopedNoDenormals guard;
    EXPECT_EQ(subnormal_product(), 0.0);
    {
      const hd::ScopedNoDenormals nested;
      EXPECT_EQ(subnormal_product(), 0.0);
    }
    EXPECT_EQ(subnormal_product(), 0.0) << "an inner guard gives back the outer's mode";
  }
  EXPECT_EQ(std::fpclassify(subnormal_product()), FP_SUBNORMAL) << "the mode before is restored";
#endif
}
