#include "eval/map/occupancy_agreement.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cenote::eval {
namespace {

TEST(OccupancyAgreement, EmptyTableGivesNaNRatios) {
  const OccupancyAgreement a = summarizeAgreement({});
  EXPECT_EQ(a.known_either, 0);
  EXPECT_TRUE(std::isnan(a.agreement));
  EXPECT_TRUE(std::isnan(a.occupied_iou));
}

TEST(OccupancyAgreement, HandComputedTable) {
  OccupancyConfusion c;
  const auto add = [&](Occupancy e, Occupancy r, int n) {
    for (int i = 0; i < n; ++i) c.add(e, r);
  };
  add(Occupancy::kOccupied, Occupancy::kOccupied, 6);
  add(Occupancy::kOccupied, Occupancy::kFree, 2);
  add(Occupancy::kFree, Occupancy::kOccupied, 1);
  add(Occupancy::kFree, Occupancy::kFree, 30);
  add(Occupancy::kUnknown, Occupancy::kOccupied, 3);
  add(Occupancy::kFree, Occupancy::kUnknown, 8);
  c.within_voxel = 45;
  const OccupancyAgreement a = summarizeAgreement(c);
  EXPECT_EQ(a.known_either, 50);
  EXPECT_EQ(a.known_both, 39);
  EXPECT_DOUBLE_EQ(a.agreement, 36.0 / 50.0);
  EXPECT_DOUBLE_EQ(a.known_agreement, 36.0 / 39.0);
  EXPECT_DOUBLE_EQ(a.occupied_precision, 6.0 / 8.0);
  EXPECT_DOUBLE_EQ(a.occupied_recall, 6.0 / 10.0);
  EXPECT_DOUBLE_EQ(a.occupied_iou, 6.0 / 12.0);
  EXPECT_DOUBLE_EQ(a.agreement_within_voxel, 45.0 / 50.0);
  const std::string json = toJson(a, c, "a.vdb", "b.bt", 0.05);
  for (const char* key :
       {"\"agreement\"", "\"known_agreement\"", "\"occupied_iou\"", "\"agreement_within_voxel\"", "\"confusion\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key;
  }
}

}  // namespace
}  // namespace cenote::eval
