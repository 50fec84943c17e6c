// SharedArray behaves as a value whether it owns its elements or shares them:
// reads of a shared array never copy, any change copies first and leaves the
// shared memory and other copies untouched, and letting go of the last
// shared array lets go of the memory's keeper.
#include "core/shared_array.h"

#include <gtest/gtest.h>

#include <memory>
#include <utility>
#include <vector>

namespace ferry {
namespace {

struct Mapping {
  std::vector<int> bytes{1, 2, 3, 4, 5};
};

SharedArray<int> sharedFirstFour(const std::shared_ptr<Mapping>& m) {
  return SharedArray<int>::shared(m->bytes.data(), 4, m, true);
}

TEST(SharedArray, ReadsASharedArrayInPlace) {
  auto m = std::make_shared<Mapping>();
  const SharedArray<int> a = sharedFirstFour(m);
  EXPECT_TRUE(a.isShared());
  EXPECT_EQ(a.data(), m->bytes.data());
  EXPECT_EQ(a.size(), 4u);
  EXPECT_EQ(a[3], 4);
  EXPECT_EQ(a.back(), 4);
  EXPECT_TRUE(a.hasSpareElement());
  EXPECT_EQ(a.ownedBytes(), 0u);
  int sum = 0;
  for (int x : a) sum += x;
  EXPECT_EQ(sum, 10);
  EXPECT_THROW(a.at(4), std::out_of_range);
}

TEST(SharedArray, ChangingACopyCopiesAndLeavesTheSharedMemoryAlone) {
  auto m = std::make_shared<Mapping>();
  const SharedArray<int> a = sharedFirstFour(m);
  SharedArray<int> b = a;  // shares too
  EXPECT_TRUE(b.isShared());
  EXPECT_EQ(std::as_const(b).data(), a.data());  // (a non-const data() would copy)
  b[0] = 9;                                      // non-const access: b becomes owned first
  EXPECT_FALSE(b.isShared());
  EXPECT_EQ(b[0], 9);
  EXPECT_EQ(a[0], 1);
  EXPECT_EQ(m->bytes[0], 1);
  EXPECT_TRUE(b.hasSpareElement());  // the copy keeps the promise
  b.push_back(7);
  EXPECT_EQ(b.size(), 5u);
  EXPECT_EQ(b.back(), 7);
  EXPECT_EQ(a.size(), 4u);
}

TEST(SharedArray, TheLastArrayLetsGoOfTheKeeper) {
  auto m = std::make_shared<Mapping>();
  std::weak_ptr<Mapping> watch = m;
  SharedArray<int> a = sharedFirstFour(m);
  SharedArray<int> moved = std::move(a);
  EXPECT_TRUE(a.empty());
  EXPECT_FALSE(a.isShared());
  m.reset();
  EXPECT_FALSE(watch.expired());
  EXPECT_EQ(moved[2], 3);
  moved.clear();
  EXPECT_TRUE(watch.expired());
  EXPECT_TRUE(moved.empty());
}

TEST(SharedArray, OwnedArraysWorkAsVectors) {
  SharedArray<int> a = std::vector<int>{1, 2};
  a.reserve(10);
  a.push_back(3);
  const std::vector<int> more{4, 5};
  a.insert(a.end(), more.begin(), more.end());
  a.resize(6, 6);
  EXPECT_EQ(a, (SharedArray<int>{1, 2, 3, 4, 5, 6}));
  SharedArray<int> copy = a;
  copy[0] = 0;
  EXPECT_EQ(a[0], 1);
  EXPECT_NE(copy.data(), a.data());
  a.pop_back();
  EXPECT_EQ(a.size(), 5u);
  EXPECT_FALSE(a.isShared());
  EXPECT_GE(a.ownedBytes(), 5 * sizeof(int));
}

}  // namespace
}  // namespace ferry
