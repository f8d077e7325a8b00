#include "io/image/mat_recycler.h"

#include <gtest/gtest.h>

namespace cenote::io {
namespace {

// An image is handed out again only once every header sharing it is gone, and only for its size
// and type.
TEST(MatRecycler, ReusesOnlyReleasedImagesOfTheSameShape) {
  MatRecycler recycler(4);
  cv::Mat a = recycler.take(6, 8, CV_32FC1);
  const cv::Mat b = recycler.take(6, 8, CV_32FC1);
  EXPECT_NE(a.data, b.data);
  const uchar* memory = a.data;
  cv::Mat copy = a;  // a second header: still held
  a.release();
  EXPECT_NE(recycler.take(6, 8, CV_32FC1).data, memory);
  copy.release();
  const cv::Mat other_type = recycler.take(6, 8, CV_8UC1);
  EXPECT_NE(other_type.data, memory);
  EXPECT_EQ(other_type.type(), CV_8UC1);
  const cv::Mat again = recycler.take(6, 8, CV_32FC1);
  EXPECT_EQ(again.data, memory);
  EXPECT_EQ(again.rows, 6);
  EXPECT_EQ(again.cols, 8);
}

// Beyond max_kept a new image is not kept, unless a free one of another shape makes room.
TEST(MatRecycler, KeepsAtMostMaxKept) {
  MatRecycler recycler(1);
  cv::Mat kept = recycler.take(4, 4, CV_8UC1);
  const uchar* kept_memory = kept.data;
  cv::Mat extra = recycler.take(4, 4, CV_8UC1);  // the kept one is held: a new one, not kept
  EXPECT_NE(extra.data, kept_memory);
  kept.release();
  EXPECT_EQ(extra.u->refcount, 1);  // not kept: the recycler is full
  extra.release();
  EXPECT_EQ(recycler.take(4, 4, CV_8UC1).data, kept_memory);
  cv::Mat larger = recycler.take(5, 5, CV_8UC1);  // made while the free 4x4 one exists, then kept in its place
  EXPECT_NE(larger.data, kept_memory);
  const uchar* larger_memory = larger.data;
  EXPECT_EQ(larger.u->refcount, 2);  // the recycler holds it too: kept (an address alone could be malloc's reuse)
  larger.release();
  EXPECT_EQ(recycler.take(5, 5, CV_8UC1).data, larger_memory);
}

}  // namespace
}  // namespace cenote::io
