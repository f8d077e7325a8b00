#include "sim/rounded_path.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cenote::sim {
namespace {

TEST(RoundedPath, IsContinuousAndClosed) {
  const RoundedPath path({{0, 0}, {4, 0}, {4, 2}, {0, 2}}, 0.5);
  EXPECT_NEAR(path.length_m(), 2 * (4 + 2) - 8 * 0.5 + 2 * M_PI * 0.5, 1e-9);
  for (double s = 0; s < path.length_m(); s += 0.01) {
    EXPECT_NEAR((path.position(s + 0.01) - path.position(s)).norm(), 0.01, 1e-6) << "s = " << s;
    EXPECT_NEAR(path.tangent(s).norm(), 1.0, 1e-9);
  }
  EXPECT_NEAR((path.position(path.length_m()) - path.position(0)).norm(), 0.0, 1e-9);
}

}  // namespace
}  // namespace cenote::sim
