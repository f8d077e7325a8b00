#include "common/text_parse.h"

#include <gtest/gtest.h>

namespace cenote {
namespace {

TEST(ParseNumberList, EmptyTextIsNoNumbers) {
  std::vector<double> v{1.0};
  EXPECT_TRUE(parseNumberList("", ',', v));
  EXPECT_TRUE(v.empty());
}

TEST(ParseNumberList, ReadsEachItemWholeAndNamesTheFirstBadOne) {
  std::vector<double> v;
  EXPECT_TRUE(parseNumberList("1.5,-2,3e2,", ',', v));  // a trailing separator ends the list
  EXPECT_EQ(v, (std::vector<double>{1.5, -2.0, 300.0}));
  std::string bad;
  EXPECT_FALSE(parseNumberList("1,2x,3", ',', v, &bad));
  EXPECT_EQ(bad, "2x");
  EXPECT_FALSE(parseNumberList("1,,3", ',', v, &bad));
  EXPECT_EQ(bad, "");
  EXPECT_FALSE(parseNumberList("1,abc", ',', v, &bad));
  EXPECT_EQ(bad, "abc");
}

TEST(ParsePoint, ExactlyThreeNumbers) {
  ASSERT_TRUE(parsePoint("1,-2,0.5").has_value());
  EXPECT_EQ(*parsePoint("1,-2,0.5"), Eigen::Vector3d(1.0, -2.0, 0.5));
  EXPECT_FALSE(parsePoint("1,2").has_value());
  EXPECT_FALSE(parsePoint("1,2,3,4").has_value());
  EXPECT_FALSE(parsePoint("1,2,z").has_value());
  EXPECT_FALSE(parsePoint("").has_value());
}

}  // namespace
}  // namespace cenote
