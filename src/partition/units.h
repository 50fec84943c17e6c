// The units partitioners deal out, and what a set of them costs.
//
// A unit is a group of instances that always goes to the same ranks:
//   - Instances: every instance on its own (spatial, bvh-style, best);
//   - Objects: all instances of an object together (object partitioners).
// Non-instanced content (objects placed once) is one unit per instance, which
// after splitForPartitioning is one unit per mesh (Zellmann et al.); or, with
// `nonInstancedTogether`, one single unit holding all of it, as the paper's
// scenes keep all non-instanced geometry in one root object (the green
// curves of its Figure 4).
//
// Cost is the memory estimate (scene/memory_cost.h): a unit's own instance
// records, plus the meshes and textures it uses. Meshes and textures are
// shared: a part pays for each once, however many of its units use it, so
// the cost of a part equals ownedMemory() of its instances.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace ferry {

struct Scene;

enum class UnitGrouping { Instances, Objects };

struct UnitOptions {
  UnitGrouping grouping = UnitGrouping::Instances;
  bool nonInstancedTogether = false;
};

struct Unit {
  std::vector<int32_t> instances;  // ascending
  Box3f bounds;                    // world space; empty if the unit has no geometry
  uint64_t ownBytes = 0;           // its instance records
  uint32_t firstResource = 0;  // its meshes and textures: UnitSet::resources[first, first + count)
  uint32_t resourceCount = 0;
  bool nonInstanced = false;  // its object(s) are placed once
  int32_t object = -1;        // the object all its instances place; -1 if several
};

struct UnitSet {
  std::vector<Unit> units;
  std::vector<uint32_t> resources;      // per unit, ascending resource ids
  std::vector<uint64_t> resourceBytes;  // resource id: meshes first, then textures
  uint32_t meshResources = 0;           // resource ids below this are meshes
  uint32_t objectCount = 0;             // of the scene (Unit::object is below this)
  std::vector<int32_t> unitOfInstance;  // per scene instance; -1 for none
};

UnitSet extractUnits(const Scene& scene, const UnitOptions& options);
// World bounds of every instance (object bounds through its transform).
std::vector<Box3f> instanceWorldBounds(const Scene& scene);

// Bytes of a set of units, shared resources counted once. Reusable: clear()
// starts a new set in O(1).
class CostCounter {
 public:
  explicit CostCounter(const UnitSet& units);
  void clear();
  // Adds a unit; returns how many bytes it added.
  uint64_t add(uint32_t unit);
  // Bytes a unit would add, without adding it.
  uint64_t marginal(uint32_t unit) const;
  uint64_t bytes() const { return bytes_; }

 private:
  const UnitSet* set_;
  std::vector<uint32_t> stamp_;
  uint32_t generation_ = 1;
  uint64_t bytes_ = 0;
};

uint64_t costOf(const UnitSet& units, const std::vector<uint32_t>& members);

// What a unit costs alone: its records and every resource it uses.
uint64_t aloneBytes(const UnitSet& units, uint32_t unit);

}  // namespace ferry
