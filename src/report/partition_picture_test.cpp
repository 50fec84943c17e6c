#include "report/partition_picture.h"

#include <gtest/gtest.h>

#include <cmath>

#include "builtin/builtin.h"
#include "report/canvas.h"
#include "scene/scene.h"

namespace ferry {
namespace {

// Is `c` the rank colour `r` scaled by some shade (as the picture shades it)?
bool isShadeOf(const uint8_t* c, Rgba r) {
  const float s = float(c[0] + c[1] + c[2]) / float(r.r + r.g + r.b);
  if (s <= 0.05f || s > 1.01f) return false;
  return std::abs(c[0] - r.r * s) <= 3 && std::abs(c[1] - r.g * s) <= 3 &&
         std::abs(c[2] - r.b * s) <= 3;
}

struct Counts {
  int background = 0, first = 0, second = 0, other = 0;
};

Counts classify(const std::vector<uint8_t>& rgba, Rgba a, Rgba b) {
  Counts n;
  for (size_t i = 0; i < rgba.size(); i += 4) {
    const uint8_t* c = &rgba[i];
    if (c[0] == 236 && c[1] == 238 && c[2] == 242)
      ++n.background;
    else if (isShadeOf(c, a))
      ++n.first;
    else if (isShadeOf(c, b))
      ++n.second;
    else
      ++n.other;
  }
  return n;
}

}  // namespace

TEST(PartitionPicture, ColoursContentByOwnerAndCheckerboardsReplicas) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  PictureOptions o;
  o.width = 96;
  o.height = 96;
  o.proxies = false;
  Partition p = roundRobinPartition(scene, 4);
  for (RankSet& m : p.instanceOwners) m = RankSet::single(3);
  Counts one = classify(partitionPicture(scene, p, o), rankColor(3), rankColor(1));
  EXPECT_GT(one.first, 96 * 96 / 2);  // the box fills most of the view
  EXPECT_EQ(one.second, 0);
  EXPECT_EQ(one.other, 0);

  for (RankSet& m : p.instanceOwners) m = RankSet::single(1) | RankSet::single(2);
  Counts two = classify(partitionPicture(scene, p, o), rankColor(1), rankColor(2));
  EXPECT_EQ(two.other, 0);
  EXPECT_GT(two.first, 96 * 96 / 5);
  EXPECT_GT(two.second, 96 * 96 / 5);
  EXPECT_EQ(two.background, one.background);
}

TEST(PartitionPicture, DrawsProxyOutlines) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  PictureOptions o;
  o.width = 96;
  o.height = 96;
  Partition p = roundRobinPartition(scene, 4);
  o.proxies = false;
  std::vector<uint8_t> without = partitionPicture(scene, p, o);
  o.proxies = true;
  std::vector<uint8_t> with = partitionPicture(scene, p, o);
  size_t changed = 0;
  for (size_t i = 0; i < with.size(); i += 4)
    changed += with[i] != without[i] || with[i + 1] != without[i + 1];
  EXPECT_GT(changed, 96u * 2);        // at least a couple of box edges across the image
  EXPECT_LT(changed, 96u * 96u / 2);  // outlines, not filled boxes
}

}  // namespace ferry
