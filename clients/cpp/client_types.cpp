// client_types.cpp: names of the client's enums, and batching.h's point-batch split.
#include "clients/cpp/batching.h"
#include "clients/cpp/client_types.h"
#include "common/enum_names.h"

namespace cenote::client {

const char* toString(VoxelState state) {
  constexpr EnumName<VoxelState> kNames[] = {
      {VoxelState::kUnknown, "unknown"}, {VoxelState::kFree, "free"}, {VoxelState::kOccupied, "occupied"}};
  return enumName(kNames, state, "invalid");
}

std::vector<PointBatch> splitPointBatch(const PointBatch& batch, size_t max_points) {
  std::vector<PointBatch> out;
  for (const auto& [begin, end] : batchRanges(batch.points_m.size(), max_points)) {
    PointBatch part;
    part.timestamp_s = batch.timestamp_s;
    part.origin_m = batch.origin_m;
    part.points_m.assign(batch.points_m.begin() + static_cast<std::ptrdiff_t>(begin),
                         batch.points_m.begin() + static_cast<std::ptrdiff_t>(end));
    if (!batch.rgb.empty()) {
      part.rgb.assign(batch.rgb.begin() + static_cast<std::ptrdiff_t>(begin),
                      batch.rgb.begin() + static_cast<std::ptrdiff_t>(end));
    }
    out.push_back(std::move(part));
  }
  return out;
}

}  // namespace cenote::client
