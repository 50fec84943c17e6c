#include "partition/units.h"

#include <algorithm>

#include "scene/memory_cost.h"
#include "scene/scene.h"

namespace ferry {

std::vector<Box3f> instanceWorldBounds(const Scene& scene) {
  std::vector<Box3f> objectBounds(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o)
    objectBounds[o] = scene.objectBounds(int32_t(o));
  std::vector<Box3f> bounds(scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i)
    bounds[i] = scene.instances[i].placeBox(objectBounds[scene.instances[i].object]);
  return bounds;
}

UnitSet extractUnits(const Scene& scene, const UnitOptions& options) {
  UnitSet set;
  const uint32_t meshes = uint32_t(scene.meshes.size());
  set.meshResources = meshes;
  set.objectCount = uint32_t(scene.objects.size());
  const uint32_t tables = meshes + uint32_t(scene.textures.size());        // first table's resource
  const uint32_t geometries = tables + uint32_t(scene.bsdfTables.size());  // first geometry's
  set.resourceBytes.reserve(geometries + scene.geometries.size());
  for (const Mesh& m : scene.meshes) set.resourceBytes.push_back(meshCost(m).total());
  for (const Texture& t : scene.textures) set.resourceBytes.push_back(textureCost(t).total());
  for (const auto& t : scene.bsdfTables) set.resourceBytes.push_back(bsdfTableCost(*t).total());
  for (const Geometry& g : scene.geometries) set.resourceBytes.push_back(geometryCost(g).total());

  // Resources of each object: its meshes and geometries and their materials'
  // textures and tables.
  std::vector<std::vector<uint32_t>> objectResources(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    std::vector<uint32_t>& r = objectResources[o];
    auto materialResources = [&](int32_t material) {
      scene.forEachShadingTexture(material, [&](int32_t t) { r.push_back(meshes + uint32_t(t)); });
      scene.forEachShadingBsdfTable(material,
                                    [&](int32_t t) { r.push_back(tables + uint32_t(t)); });
    };
    for (int32_t m : scene.objects[o].meshes) {
      r.push_back(uint32_t(m));
      materialResources(scene.meshes[m].material);
    }
    for (int32_t g : scene.objects[o].geometries) {
      r.push_back(geometries + uint32_t(g));
      materialResources(scene.geometries[g].material);
    }
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }

  const std::vector<uint32_t> instanceCount = scene.instanceCountPerObject();
  const std::vector<Box3f> bounds = instanceWorldBounds(scene);
  set.unitOfInstance.assign(scene.instances.size(), -1);

  // Group instances: a key per instance, units in order of first instance.
  std::vector<int32_t> unitOfObject(scene.objects.size(), -1);
  int32_t rootUnit = -1;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const int32_t object = scene.instances[i].object;
    const bool single = instanceCount[object] == 1;
    int32_t u = -1;
    if (single && options.nonInstancedTogether) {
      if (rootUnit < 0) {
        rootUnit = int32_t(set.units.size());
        set.units.emplace_back();
      }
      u = rootUnit;
    } else if (!single && options.grouping == UnitGrouping::Objects) {
      if (unitOfObject[object] < 0) {
        unitOfObject[object] = int32_t(set.units.size());
        set.units.emplace_back();
      }
      u = unitOfObject[object];
    } else {
      u = int32_t(set.units.size());
      set.units.emplace_back();
    }
    Unit& unit = set.units[u];
    unit.object = unit.instances.empty() || unit.object == object ? object : -1;
    unit.instances.push_back(int32_t(i));
    unit.bounds.extend(bounds[i]);
    unit.nonInstanced = single;
    set.unitOfInstance[i] = u;
  }

  std::vector<uint32_t> scratch;
  for (Unit& unit : set.units) {
    unit.ownBytes = instanceCost(unit.instances.size()).total();
    scratch.clear();
    for (int32_t i : unit.instances) {
      const auto& r = objectResources[scene.instances[i].object];
      scratch.insert(scratch.end(), r.begin(), r.end());
    }
    std::sort(scratch.begin(), scratch.end());
    scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
    unit.firstResource = uint32_t(set.resources.size());
    unit.resourceCount = uint32_t(scratch.size());
    set.resources.insert(set.resources.end(), scratch.begin(), scratch.end());
  }
  return set;
}

CostCounter::CostCounter(const UnitSet& units)
    : set_(&units), stamp_(units.resourceBytes.size(), 0) {}

void CostCounter::clear() {
  bytes_ = 0;
  if (++generation_ == 0) {  // wrapped: forget every old stamp
    std::fill(stamp_.begin(), stamp_.end(), 0);
    generation_ = 1;
  }
}

uint64_t CostCounter::add(uint32_t unit) {
  const Unit& u = set_->units[unit];
  uint64_t added = u.ownBytes;
  for (uint32_t k = 0; k < u.resourceCount; ++k) {
    uint32_t r = set_->resources[u.firstResource + k];
    if (stamp_[r] != generation_) {
      stamp_[r] = generation_;
      added += set_->resourceBytes[r];
    }
  }
  bytes_ += added;
  return added;
}

uint64_t CostCounter::marginal(uint32_t unit) const {
  const Unit& u = set_->units[unit];
  uint64_t added = u.ownBytes;
  for (uint32_t k = 0; k < u.resourceCount; ++k) {
    uint32_t r = set_->resources[u.firstResource + k];
    if (stamp_[r] != generation_) added += set_->resourceBytes[r];
  }
  return added;
}

uint64_t costOf(const UnitSet& units, const std::vector<uint32_t>& members) {
  CostCounter c(units);
  for (uint32_t u : members) c.add(u);
  return c.bytes();
}

uint64_t aloneBytes(const UnitSet& units, uint32_t unit) {
  const Unit& u = units.units[unit];
  uint64_t bytes = u.ownBytes;
  for (uint32_t k = 0; k < u.resourceCount; ++k)
    bytes += units.resourceBytes[units.resources[u.firstResource + k]];
  return bytes;
}

}  // namespace ferry
