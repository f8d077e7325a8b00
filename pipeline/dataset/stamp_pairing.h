// stamp_pairing.h: left and right images paired by their header stamps within a tolerance
// (approximate time synchronisation), streamed, with a bounded look-ahead.
//
// The rule: a left image l and a right image r are a pair when |t_l - t_r| <= tolerance and each is
// the other's nearest image of the other camera (ties go to the earlier image). Everything else is
// unpaired and counted, never paired with something else: a dropped right image leaves its left one
// unpaired rather than matched to the next right image. The rule depends only on the stamps, so the
// pairs are those an offline pass over the sorted stamps finds (tests/pipeline/dataset/).
// Streaming: an image is decided once every image up to its stamp + 2 * tolerance has been pushed
// (or its camera's stream has ended). When more than `max_pending` images wait (one camera fell
// silent), the oldest is decided with what is known; one that might still pair is counted unpaired
// rather than guessed, so a pair is never wrong.
// Stamps within one camera must increase; an image whose stamp is not after its camera's previous
// one is counted unpaired (out of order).
// Units: nanoseconds. Threads: one user.
#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <utility>

namespace cenote::pipeline {

enum class StereoSide { kLeft = 0, kRight = 1 };

template <class T>
class StampPairer {
 public:
  struct Item {
    std::int64_t stamp_ns = 0;
    T value;
  };
  struct Pair {
    Item left, right;
  };

  /// @param tolerance_ns >= 0. @param max_pending images held at most (>= 2).
  StampPairer(std::int64_t tolerance_ns, std::size_t max_pending) : tol_(tolerance_ns), max_pending_(max_pending) {}

  /// An image of one camera, in that camera's stamp order.
  void push(StereoSide side, std::int64_t stamp_ns, T value) {
    const int s = static_cast<int>(side);
    if (seen_any_[s] && stamp_ns <= last_seen_[s]) {
      ++unpaired_;
      ++out_of_order_;
      return;
    }
    seen_any_[s] = true;
    last_seen_[s] = stamp_ns;
    q_[s].push_back({stamp_ns, std::move(value)});
  }

  /// No more images of this camera.
  void finish(StereoSide side) { ended_[static_cast<int>(side)] = true; }

  /// The next pair, in stamp order; nullopt when more images must be pushed first (or, once both
  /// cameras have finished, when there are none left).
  std::optional<Pair> pop() {
    while (!q_[0].empty() || !q_[1].empty()) {
      const int a = q_[1].empty() || (!q_[0].empty() && q_[0].front().stamp_ns <= q_[1].front().stamp_ns) ? 0 : 1;
      const int o = 1 - a;
      const std::int64_t ta = q_[a].front().stamp_ns;
      const bool forced = q_[0].size() + q_[1].size() > max_pending_;
      if (!forced && !(knownUpTo(0, ta + 2 * tol_) && knownUpTo(1, ta + 2 * tol_))) return std::nullopt;
      if (pairsWithNext(a, o, ta)) {
        Pair pair;
        Item& first = q_[a].front();
        Item& second = q_[o].front();
        consumed_[a] = first.stamp_ns;
        consumed_[o] = second.stamp_ns;
        has_consumed_[a] = has_consumed_[o] = true;
        pair.left = std::move(a == 0 ? first : second);
        pair.right = std::move(a == 0 ? second : first);
        q_[0].pop_front();
        q_[1].pop_front();
        ++pairs_;
        return pair;
      }
      consumed_[a] = ta;
      has_consumed_[a] = true;
      q_[a].pop_front();
      ++unpaired_;
    }
    return std::nullopt;
  }

  /// Images counted unpaired so far (out-of-order ones included), and of those the out-of-order ones.
  std::uint64_t unpaired() const { return unpaired_; }
  std::uint64_t outOfOrder() const { return out_of_order_; }
  std::uint64_t pairs() const { return pairs_; }
  /// Images waiting (never above max_pending + 1).
  std::size_t pending() const { return q_[0].size() + q_[1].size(); }

 private:
  // Every image of camera s with a stamp <= t has been pushed.
  bool knownUpTo(int s, std::int64_t t) const { return ended_[s] || (seen_any_[s] && last_seen_[s] >= t); }

  // Whether the earliest image (camera a, stamp ta) pairs with the first image of camera o.
  bool pairsWithNext(int a, int o, std::int64_t ta) const {
    if (q_[o].empty()) return false;
    const std::int64_t tb = q_[o].front().stamp_ns;
    const std::int64_t d = tb - ta;  // >= 0: a is the earliest
    if (d > tol_) return false;
    // a's nearest of camera o: the last one decided before it or b; a tie goes to the earlier.
    if (has_consumed_[o] && ta - consumed_[o] <= d) return false;
    // b's nearest of camera a: a or the next one of camera a; a tie goes to a.
    if (q_[a].size() >= 2) return q_[a][1].stamp_ns - tb >= d;
    return knownUpTo(a, tb + d);  // no next one of camera a within d of b (else it might still come)
  }

  std::int64_t tol_;
  std::size_t max_pending_;
  std::deque<Item> q_[2];
  std::int64_t last_seen_[2] = {0, 0};
  bool seen_any_[2] = {false, false};
  bool ended_[2] = {false, false};
  std::int64_t consumed_[2] = {0, 0};
  bool has_consumed_[2] = {false, false};
  std::uint64_t unpaired_ = 0, out_of_order_ = 0, pairs_ = 0;
};

}  // namespace cenote::pipeline
