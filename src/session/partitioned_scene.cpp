#include "session/partitioned_scene.h"

#include "io/parts/part_directory.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"

namespace ferry {

PartitionedScene loadPartitionedScene(const SessionSettings& settings, int ranks, int rank,
                                      Scene* given,
                                      const std::function<void(Scene&)>& beforePartition) {
  PartitionedScene out;
  if (!given && isPartDirectory(settings.scene)) {
    if (rank >= 0) {
      RankPart part = loadRankPart(settings.scene, rank, ranks);
      out.scene = std::move(part.scene);
      out.partition = std::move(part.partition);
      out.lights = std::move(part.lights);
      out.manifest = std::move(part.manifest);
    } else {
      out.scene = loadAllParts(settings.scene, out.partition);
      out.manifest = readManifest(settings.scene);
    }
    out.partitioner = out.manifest->partitioner;
    return out;
  }
  out.scene = given ? std::move(*given) : loadScene(settings.scene, settings.load);
  if (beforePartition) beforePartition(out.scene);
  const PartitionerOptions options = partitionerOptions(settings, ranks);
  out.partition = partitionScene(out.scene, ranks, options);
  out.partitioner = options.chosen().name();
  return out;
}

}  // namespace ferry
