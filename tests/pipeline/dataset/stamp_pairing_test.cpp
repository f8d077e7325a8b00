// StampPairer against an offline reference: the pairs are the mutual nearest stamps within the
// tolerance over the whole sorted lists, whatever order and lag the two streams arrive in.
#include "pipeline/dataset/stamp_pairing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <utility>
#include <vector>

namespace cenote::pipeline {
namespace {

using Pairs = std::vector<std::pair<std::int64_t, std::int64_t>>;

// The nearest of `others` to t (ties to the earlier), or -1.
int nearest(const std::vector<std::int64_t>& others, std::int64_t t) {
  int best = -1;
  for (int i = 0; i < static_cast<int>(others.size()); ++i) {
    if (best < 0 || std::llabs(others[i] - t) < std::llabs(others[best] - t)) best = i;
  }
  return best;
}

Pairs referencePairs(const std::vector<std::int64_t>& left, const std::vector<std::int64_t>& right, std::int64_t tol) {
  Pairs pairs;
  for (std::int64_t l : left) {
    const int r = nearest(right, l);
    if (r < 0 || std::llabs(right[r] - l) > tol) continue;
    if (left[nearest(left, right[r])] == l) pairs.emplace_back(l, right[r]);
  }
  return pairs;
}

struct Result {
  Pairs pairs;
  std::uint64_t unpaired = 0;
  std::size_t max_pending = 0;
};

// Pushes the two streams interleaved as a recorder writes them (the right stream `lag` messages
// behind), popping whatever is decided after each push.
Result run(const std::vector<std::int64_t>& left, const std::vector<std::int64_t>& right, std::int64_t tol, std::size_t lag,
           std::size_t queue = 64) {
  StampPairer<int> pairer(tol, queue);
  Result out;
  auto drain = [&] {
    while (auto p = pairer.pop()) out.pairs.emplace_back(p->left.stamp_ns, p->right.stamp_ns);
    out.max_pending = std::max(out.max_pending, pairer.pending());
  };
  std::size_t i = 0, j = 0;
  while (i < left.size() || j < right.size()) {
    if (i < left.size() && (i < j + lag || j >= right.size())) {
      pairer.push(StereoSide::kLeft, left[i++], 0);
    } else {
      pairer.push(StereoSide::kRight, right[j++], 0);
    }
    drain();
  }
  pairer.finish(StereoSide::kLeft);
  pairer.finish(StereoSide::kRight);
  drain();
  out.unpaired = pairer.unpaired();
  return out;
}

TEST(StampPairer, ExactStampsPairOneToOne) {
  const std::vector<std::int64_t> t = {100, 200, 300};
  const Result r = run(t, t, 0, 0);
  EXPECT_EQ(r.pairs, (Pairs{{100, 100}, {200, 200}, {300, 300}}));
  EXPECT_EQ(r.unpaired, 0u);
}

TEST(StampPairer, ADroppedRightImageLeavesItsLeftUnpairedNotMatchedToTheNext) {
  // 10 Hz, right image at 200 ms dropped, tolerance 10 ms: the left at 200 stays alone, never
  // paired with the right at 300 (100 ms off) or 100.
  const std::vector<std::int64_t> left = {100'000'000, 200'000'000, 300'000'000};
  const std::vector<std::int64_t> right = {100'003'000, 300'002'000};
  const Result r = run(left, right, 10'000'000, 1);
  EXPECT_EQ(r.pairs, (Pairs{{100'000'000, 100'003'000}, {300'000'000, 300'002'000}}));
  EXPECT_EQ(r.unpaired, 1u);
}

TEST(StampPairer, TwoCandidatesWithinToleranceGoToTheNearest) {
  // The right at 104 is nearer to the left at 106 than to 100: 100 stays unpaired, not 106.
  const Result r = run({100, 106}, {104}, 10, 0);
  EXPECT_EQ(r.pairs, (Pairs{{106, 104}}));
  EXPECT_EQ(r.unpaired, 1u);
  // Equal distances go to the earlier image.
  const Result tie = run({100, 108}, {104}, 10, 0);
  EXPECT_EQ(tie.pairs, (Pairs{{100, 104}}));
}

TEST(StampPairer, OutOfOrderStampIsCountedUnpaired) {
  StampPairer<int> pairer(5, 64);
  pairer.push(StereoSide::kLeft, 100, 0);
  pairer.push(StereoSide::kLeft, 90, 0);  // before its predecessor
  pairer.push(StereoSide::kRight, 101, 0);
  pairer.finish(StereoSide::kLeft);
  pairer.finish(StereoSide::kRight);
  const auto p = pairer.pop();
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->left.stamp_ns, 100);
  EXPECT_FALSE(pairer.pop().has_value());
  EXPECT_EQ(pairer.unpaired(), 1u);
  EXPECT_EQ(pairer.outOfOrder(), 1u);
}

TEST(StampPairer, JitteredStampsGiveExactlyTheReferencePairsForAnyLag) {
  // 20 Hz cameras, 5 % of the images of each camera dropped, fixed seed; stamps jittered by up to
  // +-4 ms (tolerance 10 ms) and by up to +-20 ms (tolerance 25 ms, where nearest neighbours compete).
  for (const auto& [jitter_ns, tol] :
       {std::pair{4'000'000, std::int64_t{10'000'000}}, std::pair{20'000'000, std::int64_t{25'000'000}}}) {
    std::mt19937 rng(15);
    std::uniform_int_distribution<int> jitter(-jitter_ns, jitter_ns);
    std::uniform_real_distribution<double> drop(0.0, 1.0);
    std::vector<std::int64_t> left, right;
    for (int i = 0; i < 2000; ++i) {
      const std::int64_t t = 1'700'000'000'000'000'000 + std::int64_t{i} * 50'000'000;
      if (drop(rng) > 0.05) left.push_back(t + jitter(rng));
      if (drop(rng) > 0.05) right.push_back(t + jitter(rng));
    }
    const Pairs expected = referencePairs(left, right, tol);
    const std::uint64_t expected_unpaired = left.size() + right.size() - 2 * expected.size();
    ASSERT_GT(expected.size(), 1500u) << "jitter " << jitter_ns;
    for (std::size_t lag : {0, 1, 3, 10}) {
      const Result r = run(left, right, tol, lag);
      EXPECT_EQ(r.pairs, expected) << "jitter " << jitter_ns << " lag " << lag;
      EXPECT_EQ(r.unpaired, expected_unpaired) << "jitter " << jitter_ns << " lag " << lag;
      EXPECT_LE(r.max_pending, 65u) << "lag " << lag;
    }
  }
}

TEST(StampPairer, ASilentCameraBoundsTheQueueAndNeverPairsWrongly) {
  // The right camera stops for 300 images, then resumes: the left images meanwhile are decided
  // with a queue of 16 and counted unpaired; every pair made is a reference pair.
  std::vector<std::int64_t> left, right;
  for (int i = 0; i < 600; ++i) {
    left.push_back(std::int64_t{i} * 50'000'000);
    if (i < 100 || i >= 400) right.push_back(std::int64_t{i} * 50'000'000 + 1'000'000);
  }
  const Pairs expected = referencePairs(left, right, 10'000'000);
  // Right images arrive late: the whole silent stretch of left images comes first.
  const Result r = run(left, right, 10'000'000, 400, 16);
  EXPECT_LE(r.max_pending, 17u);
  for (const auto& p : r.pairs) EXPECT_NE(std::find(expected.begin(), expected.end(), p), expected.end());
  EXPECT_EQ(r.unpaired, left.size() + right.size() - 2 * r.pairs.size());
}

}  // namespace
}  // namespace cenote::pipeline
