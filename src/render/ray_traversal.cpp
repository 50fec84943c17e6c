#include "render/ray_traversal.h"

#include <chrono>

#include "render/path.h"

namespace ferry {

template <typename Path>
void traceLocally(const LocalGeometry& geometry, std::vector<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, FrameStats& stats) {
  auto start = std::chrono::steady_clock::now();
  // Split by query kind so each goes to Embree as one stream.
  std::vector<uint32_t> closestIndex, shadowIndex;
  std::vector<TraceRay> closest, shadow;
  for (uint32_t i = 0; i < rays.size(); ++i) {
    const Path& p = rays[i];
    if (p.isShadow() && p.has(kPathOccluded)) continue;  // already decided elsewhere
    TraceRay r{p.origin, p.dir(), 0.0f, p.tmax};
    if (p.isShadow()) {
      shadowIndex.push_back(i);
      shadow.push_back(r);
    } else {
      closestIndex.push_back(i);
      closest.push_back(r);
    }
  }
  std::vector<TraceHit> hits(closest.size());
  geometry.intersect(closest, hits);
  for (size_t k = 0; k < closest.size(); ++k) {
    Path& p = rays[closestIndex[k]];
    if (hits[k].valid() && hits[k].t < p.tmax) {
      p.tmax = hits[k].t;
      p.setHit(rank, instanceOwners.empty() ? 0 : instanceOwners[hits[k].instance]);
    }
  }
  std::vector<uint8_t> occluded(shadow.size());
  geometry.occluded(shadow, occluded);
  for (size_t k = 0; k < shadow.size(); ++k)
    if (occluded[k]) rays[shadowIndex[k]].set(kPathOccluded);
  for (Path& p : rays) p.markTraced(rank);
  stats.closestTraces += closest.size();
  stats.occlusionTraces += shadow.size();
  stats.times.trace += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template void traceLocally<Path8>(const LocalGeometry&, std::vector<Path8>&, int, std::span<const uint64_t>,
                                  FrameStats&);
template void traceLocally<Path64>(const LocalGeometry&, std::vector<Path64>&, int, std::span<const uint64_t>,
                                   FrameStats&);
template void traceLocally<PathReplay>(const LocalGeometry&, std::vector<PathReplay>&, int,
                                       std::span<const uint64_t>, FrameStats&);

}  // namespace ferry
