// block_replay.h: the blocks a pose correction rebuilds (map_history.h, step 2): each from unknown,
// by replaying the stored updates of every frame that touches it, in the frames' order, with the
// rule OccupancyMap::publish applies (publish_word.h) and its running mean of colours; so each block
// ends as the map built from scratch with the same frames holds it, bit for bit.
// Frames are read and decoded a few at a time in parallel (each only the blocks being rebuilt),
// then merged in parallel over disjoint ranges of blocks, each range taking the frames in order:
// the result is the same for any thread count.
// Units: log-odds, voxel indices. Threads: a function; it reads the store (which no one may write
// meanwhile) and uses OpenMP internally.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "mapping/history/frame_store.h"
#include "mapping/log_odds.h"
#include "mapping/occupancy_map.h"

namespace cenote::mapping::history {

// The state of every block `keys` lists (detail::packIndex, ascending) after replaying the stored
// updates of `frames` (ascending seqs, all in `store`), in keys' order.
// @throws IoError / NotFoundError from the store (a damaged or missing file).
std::vector<BlockState> replayBlocks(const FrameStore& store, std::span<const uint32_t> frames,
                                     std::span<const uint64_t> keys, const LogOddsModel& model, int num_threads);

}  // namespace cenote::mapping::history
