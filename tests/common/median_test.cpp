#include "common/median.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cenote {
namespace {

TEST(Median, EmptyIsNaN) { EXPECT_TRUE(std::isnan(median({}))); }

TEST(Median, OddIsTheMiddleEvenTheMeanOfTheTwoMiddles) {
  EXPECT_EQ(median({7.0}), 7.0);
  EXPECT_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.5);
  std::vector<double> v{5.0, 1.0, 4.0};
  EXPECT_EQ(medianInPlace(v), 4.0);
  EXPECT_EQ(v.size(), 3u);
}

}  // namespace
}  // namespace cenote
