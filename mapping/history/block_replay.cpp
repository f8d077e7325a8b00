#include "mapping/history/block_replay.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <exception>
#include <string>

#include "mapping/detail/block_table.h"
#include "mapping/detail/publish_word.h"
#include "mapping/history/frame_codec.h"

namespace cenote::mapping::history {
namespace {

// Frames read and decoded per round: enough to keep every thread busy inflating, few enough that
// their decoded masks stay a few MB.
constexpr size_t kFramesPerRound = 8;

// A block being rebuilt: its voxels and the running mean colour of its hit voxels.
struct RebuiltBlock {
  BlockView view;
  std::vector<std::array<uint8_t, 4>> colors;  // per offset: RGB and batches averaged (0: none); empty until one
};

// One frame's updates of the blocks being rebuilt, each block and colour with its slot in `keys`.
struct DecodedFrame {
  FrameUpdates updates;               // kept_at: each block's slot
  std::vector<uint32_t> color_slots;  // the slot of each colour's block
  std::exception_ptr error;
};

void decodeFrame(const FrameStore& store, uint32_t seq, std::span<const uint64_t> keys, DecodedFrame& out) {
  out.error = nullptr;
  try {
    out.updates = decodeUpdates(store.readUpdates(seq), "frame " + std::to_string(seq), keys);
    const FrameUpdates& u = out.updates;
    out.color_slots.resize(u.colors.size());
    size_t b = 0;
    for (size_t i = 0; i < u.colors.size(); ++i) {
      const uint64_t block = detail::packIndex(blockOf(u.colors[i].ijk));
      if (u.keys[b] != block) b = std::lower_bound(u.keys.begin(), u.keys.end(), block) - u.keys.begin();
      out.color_slots[i] = u.kept_at[b];  // decodeUpdates keeps only the colours of kept blocks
    }
  } catch (...) {
    out.error = std::current_exception();
  }
}

// The rule OccupancyMap::publish applies, word by word (publish_word.h).
void mergeMasks(BlockView& view, const BlockMasks& masks, const LogOddsModel& model) {
  for (int w = 0; w < 8; ++w) {
    const uint64_t update = masks.free[w] | masks.hit[w];
    if (update == 0) continue;
    view.known[w] |= detail::publishWord(view.log_odds.data() + w * 64, view.known[w], update, masks.hit[w], model);
  }
}

// OccupancyMap::publish's running mean, saturating at 127 batches.
void mergeColor(RebuiltBlock& block, int offset, const std::array<uint8_t, 3>& rgb) {
  if (block.colors.empty()) block.colors.assign(kBlockVoxels, {0, 0, 0, 0});
  std::array<uint8_t, 4>& cell = block.colors[offset];
  const int count = cell[3];
  for (int k = 0; k < 3; ++k) cell[k] = static_cast<uint8_t>((cell[k] * count + rgb[k] + (count + 1) / 2) / (count + 1));
  cell[3] = static_cast<uint8_t>(std::min(count + 1, 127));
}

// Frame `f`'s updates of the blocks in slots [lo, hi).
void mergeFrame(const DecodedFrame& f, uint32_t lo, uint32_t hi, std::vector<RebuiltBlock>& rebuilt,
                const LogOddsModel& model) {
  const std::vector<uint32_t>& slots = f.updates.kept_at;
  const size_t begin = std::lower_bound(slots.begin(), slots.end(), lo) - slots.begin();
  for (size_t b = begin; b < slots.size() && slots[b] < hi; ++b) {
    mergeMasks(rebuilt[slots[b]].view, f.updates.masks[b], model);
  }
  for (size_t i = 0; i < f.color_slots.size(); ++i) {
    const uint32_t slot = f.color_slots[i];
    if (slot >= lo && slot < hi) mergeColor(rebuilt[slot], offsetInBlock(f.updates.colors[i].ijk), f.updates.colors[i].rgb);
  }
}

BlockState stateOf(uint64_t key, const RebuiltBlock& block) {
  BlockState state;
  state.block = detail::unpackIndex(key);
  state.view = block.view;
  for (int offset = 0; offset < static_cast<int>(block.colors.size()); ++offset) {
    const std::array<uint8_t, 4>& cell = block.colors[offset];
    if (cell[3] != 0)
      state.colors.push_back(VoxelColor{static_cast<uint16_t>(offset), {cell[0], cell[1], cell[2]}, cell[3]});
  }
  return state;
}

}  // namespace

std::vector<BlockState> replayBlocks(const FrameStore& store, std::span<const uint32_t> frames,
                                     std::span<const uint64_t> keys, const LogOddsModel& model, int num_threads) {
  const int threads = std::max(1, num_threads > 0 ? num_threads : omp_get_max_threads());
  std::vector<RebuiltBlock> rebuilt(keys.size());
  std::vector<DecodedFrame> round(kFramesPerRound);
  for (size_t first = 0; first < frames.size(); first += kFramesPerRound) {
    const int n = static_cast<int>(std::min(kFramesPerRound, frames.size() - first));
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int j = 0; j < n; ++j) decodeFrame(store, frames[first + j], keys, round[j]);
    for (int j = 0; j < n; ++j) {
      if (round[j].error) std::rethrow_exception(round[j].error);
    }
    // Each thread its own range of blocks, taking the round's frames in order.
#pragma omp parallel for num_threads(threads) schedule(static, 1)
    for (int t = 0; t < threads; ++t) {
      const auto lo = static_cast<uint32_t>(keys.size() * t / threads);
      const auto hi = static_cast<uint32_t>(keys.size() * (t + 1) / threads);
      for (int j = 0; j < n; ++j) mergeFrame(round[j], lo, hi, rebuilt, model);
    }
  }
  std::vector<BlockState> states(keys.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (size_t i = 0; i < keys.size(); ++i) states[i] = stateOf(keys[i], rebuilt[i]);
  return states;
}

}  // namespace cenote::mapping::history
