// Pictures of a partition (the paper's Figure 3): what the camera sees,
// coloured by the rank that owns it (content held by several ranks is
// checkerboarded in their colours), with every proxy drawn as a translucent
// box outline in its owner's colour (fainter where geometry hides it). A small
// renderer of its own over the trace backend, not a mode of the path tracer.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "partition/partition.h"

namespace ferry {

struct Scene;

struct PictureOptions {
  int width = 960;
  int height = 540;
  std::string view;   // empty: the scene's first view
  std::string title;  // drawn at the top left, with a legend of rank colours
  bool proxies = true;
};

// RGBA, row 0 at the top. `scene` holds all content; `partition` refers to
// its instances.
std::vector<uint8_t> partitionPicture(const Scene& scene, const Partition& partition,
                                      const PictureOptions& options);

}  // namespace ferry
