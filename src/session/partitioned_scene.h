// A scene and who owns what, from either source a render takes: a part
// directory (one rank's part, or every part), or a scene (a file, a
// built-in, or one given in memory) read whole and partitioned on the fly,
// as every rank does alike.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "comm/communicator.h"
#include "io/parts/manifest.h"
#include "partition/partition.h"
#include "scene/scene.h"
#include "session/session_settings.h"

namespace ferry {

struct PartitionedScene {
  Scene scene;  // a part, every part, or the partitioned scene (rewritten by the partitioner)
  Partition partition;               // of every rank
  std::string partitioner;           // the name of the partitioner that made it
  std::optional<Manifest> manifest;  // a part directory's
  Scene lights;                      // a part directory's light scene (scene/light_scene.h)
};

// From settings.scene (or `given`, the whole scene in memory) over `ranks`
// ranks: `rank`'s part of a part directory (rank < 0: every part), or the
// scene partitioned with partitionerOptions(settings, ranks).
// `beforePartition` sees a loaded scene as given, before the partitioner
// rewrites it. Throws InputError naming the file for what cannot be read.
PartitionedScene loadPartitionedScene(const SessionSettings& settings, int ranks, int rank,
                                      Scene* given = nullptr,
                                      const std::function<void(Scene&)>& beforePartition = {});

// This rank's own piece of a scene that is already spread over the ranks
// of `comm` (each holds only its piece, as a simulation does), with no
// partitioning step: the rank owns every instance of its piece; the proxies
// (as the partitioners make them: a mesh placed once braided into boxes, an
// instance of an instanced object its box) and the lights (every emissive
// triangle) are every rank's, exchanged, in rank order; the summary is the whole's.
// Suns, environment, views, film and media are the piece's own: every rank
// gives the same. Collective; InputError (the same on every rank) if a
// piece is not valid.
PartitionedScene distributedPiece(Scene piece, const Communicator& comm);

// The union of every rank's `box` (collective; empty boxes add nothing).
Box3f wholeBounds(const Box3f& box, const Communicator& comm);

}  // namespace ferry
