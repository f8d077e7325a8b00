#include "common/config_error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cenote {
namespace {

TEST(ConfigErrors, FormatsKeyValueAndRule) {
  ConfigErrors errors("stereo");
  errors.check(false, "num_disparities", 300, "must be a multiple of 16 in [16, 512]");
  errors.check(true, "window_px", 3, "never shown");
  const auto list = errors.take();
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].toString(), "stereo.num_disparities = 300: must be a multiple of 16 in [16, 512]");
}

// Bounds are inclusive and print as values do; a NaN is outside; the note follows the range.
TEST(ConfigErrors, RangeCheckNamesItsBounds) {
  ConfigErrors errors("viewer");
  errors.checkRange("tick_s", 0.005, 0.005, 10.0);
  errors.checkRange("tick_s", 10.0, 0.005, 10.0);
  errors.checkRange("tick_s", 10.5, 0.005, 10.0);
  errors.checkRange("refresh_s", std::nan(""), 0.0, 86400.0);
  errors.checkRange("max_cloud_points", 1000001, 0, 1000000, " (0: off)");
  errors.checkRange("k1", -1.5, -1.0, 1.0);
  const auto list = errors.take();
  ASSERT_EQ(list.size(), 4u);
  EXPECT_EQ(list[0].toString(), "viewer.tick_s = 10.5: must be in [0.005, 10]");
  EXPECT_EQ(list[1].toString(), "viewer.refresh_s = nan: must be in [0, 86400]");
  EXPECT_EQ(list[2].toString(), "viewer.max_cloud_points = 1000001: must be in [0, 1000000] (0: off)");
  EXPECT_EQ(list[3].toString(), "viewer.k1 = -1.5: must be in [-1, 1]");
}

}  // namespace
}  // namespace cenote
