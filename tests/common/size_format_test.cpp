#include "common/size_format.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cenote {
namespace {

TEST(SizeFormat, BytesBelowOneKibibyteAreWholeBytes) {
  EXPECT_EQ(formatBytes(0), "0 B");
  EXPECT_EQ(formatBytes(1), "1 B");
  EXPECT_EQ(formatBytes(1023), "1023 B");
}

TEST(SizeFormat, LargerSizesTakeTheBinaryUnitThatKeepsThemBelow1024WithThreeDigits) {
  EXPECT_EQ(formatBytes(1024), "1.00 KiB");
  EXPECT_EQ(formatBytes(1536), "1.50 KiB");
  EXPECT_EQ(formatBytes(15.3 * 1024), "15.3 KiB");
  EXPECT_EQ(formatBytes(433.0 * 1048576), "433 MiB");
  EXPECT_EQ(formatBytes(1048576), "1.00 MiB");
  EXPECT_EQ(formatBytes(12345678), "11.8 MiB");
  EXPECT_EQ(formatBytes(2.0 * 1073741824), "2.00 GiB");
  EXPECT_EQ(formatBytes(3.0 * 1099511627776), "3.00 TiB");
  EXPECT_EQ(formatBytes(2048.0 * 1125899906842624), "2048 PiB");  // the largest unit takes any size
}

TEST(SizeFormat, CountsTakeDecimalUnits) {
  EXPECT_EQ(formatCount(0), "0");
  EXPECT_EQ(formatCount(999), "999");
  EXPECT_EQ(formatCount(1000), "1.00 k");
  EXPECT_EQ(formatCount(12345), "12.3 k");
  EXPECT_EQ(formatCount(4560000), "4.56 M");
  EXPECT_EQ(formatCount(120000000), "120 M");
  EXPECT_EQ(formatCount(1.2e9), "1.20 G");
}

TEST(SizeFormat, UnknownSizeIsSaidSo) {
  EXPECT_EQ(formatBytes(-1), "unknown");
  EXPECT_EQ(formatCount(-1), "unknown");
  EXPECT_EQ(formatBytes(std::nan("")), "unknown");
}

}  // namespace
}  // namespace cenote
