#include "eval/map/occupancy_agreement.h"

#include <cmath>
#include <limits>

#include "eval/report/metrics_document.h"

namespace cenote::eval {
namespace {

double ratio(int64_t a, int64_t b) { return b > 0 ? static_cast<double>(a) / b : std::numeric_limits<double>::quiet_NaN(); }

}  // namespace

OccupancyAgreement summarizeAgreement(const OccupancyConfusion& c) {
  OccupancyAgreement a;
  int64_t same = 0, same_known = 0;
  for (int e = 0; e < 3; ++e) {
    for (int r = 0; r < 3; ++r) {
      if (e == 0 && r == 0) continue;
      const int64_t n = c.counts[e][r];
      a.known_either += n;
      if (e != 0 && r != 0) a.known_both += n;
      if (e == r) {
        same += n;
        same_known += n;
      }
      if (e == 2) a.occupied_estimate += n;
      if (r == 2) a.occupied_reference += n;
    }
  }
  const int64_t both_occupied = c.at(Occupancy::kOccupied, Occupancy::kOccupied);
  a.agreement = ratio(same, a.known_either);
  a.known_agreement = ratio(same_known, a.known_both);
  a.agreement_within_voxel = ratio(c.within_voxel, a.known_either);
  a.occupied_iou = ratio(both_occupied, a.occupied_estimate + a.occupied_reference - both_occupied);
  a.occupied_precision = ratio(both_occupied, a.occupied_estimate);
  a.occupied_recall = ratio(both_occupied, a.occupied_reference);
  return a;
}

std::string toJson(const OccupancyAgreement& a, const OccupancyConfusion& c, const std::string& estimate,
                   const std::string& reference, double voxel_size_m) {
  Json j = metricsDocument("map", "fractions; voxel_size in metres", estimate, reference);
  j["voxel_size"] = voxel_size_m;
  j["agreement"] = jsonNumber(a.agreement);
  j["known_agreement"] = jsonNumber(a.known_agreement);
  j["occupied_iou"] = jsonNumber(a.occupied_iou);
  j["occupied_precision"] = jsonNumber(a.occupied_precision);
  j["occupied_recall"] = jsonNumber(a.occupied_recall);
  j["agreement_within_voxel"] = jsonNumber(a.agreement_within_voxel);
  j["known_either"] = a.known_either;
  j["known_both"] = a.known_both;
  j["occupied_estimate"] = a.occupied_estimate;
  j["occupied_reference"] = a.occupied_reference;
  const char* names[] = {"unknown", "free", "occupied"};
  Json table;
  for (int e = 0; e < 3; ++e) {
    for (int r = 0; r < 3; ++r)
      table[std::string("estimate_") + names[e]][std::string("reference_") + names[r]] = c.counts[e][r];
  }
  j["confusion"] = table;
  return j.dump(2) + "\n";
}

}  // namespace cenote::eval
