#include "common/config_error.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace cenote
