// batching.h: splitting large point lists into requests of at most N items, as the server limits
// each request (`server.max_batch` query items, `server.max_points_per_batch` points).
// Threads: pure functions.
#pragma once

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "clients/cpp/client_types.h"

namespace cenote::client {

// [begin, end) index ranges covering 0..count in order, each at most max_items long (max_items 0:
// one range). count 0: no range.
inline std::vector<std::pair<size_t, size_t>> batchRanges(size_t count, size_t max_items) {
  std::vector<std::pair<size_t, size_t>> ranges;
  const size_t step = max_items == 0 ? std::max<size_t>(count, 1) : max_items;
  for (size_t begin = 0; begin < count; begin += step) ranges.emplace_back(begin, std::min(count, begin + step));
  return ranges;
}

// Consecutive slices of `items`, each at most max_items long, in order.
template <typename T>
std::vector<std::vector<T>> splitBatches(const std::vector<T>& items, size_t max_items) {
  std::vector<std::vector<T>> out;
  for (const auto& [begin, end] : batchRanges(items.size(), max_items)) {
    out.emplace_back(items.begin() + static_cast<std::ptrdiff_t>(begin), items.begin() + static_cast<std::ptrdiff_t>(end));
  }
  return out;
}

// A point batch split into batches of at most max_points points with the same origin and
// timestamp (colours follow their points).
// @warning the map deduplicates endpoints per batch: integrating the parts can differ from
//   integrating the whole at voxels that points of two parts share.
std::vector<PointBatch> splitPointBatch(const PointBatch& batch, size_t max_points);

}  // namespace cenote::client
