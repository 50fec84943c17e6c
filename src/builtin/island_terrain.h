// The base geometry of the island's terrain elements (docs/scenes.md), each
// made of several meshes as in Disney's Moana island, where the ground is
// the sum of the elements' own meshes rather than one heightfield: ground
// tiles (each tile goes to the element whose region holds it), the two
// peaks cut into sectors, the lava cliffs, the beach's sand in pieces, the
// reef's mounds, and the sea. Each function adds meshes to the plan and
// returns them by element name.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "builtin/island_shape.h"
#include "builtin/scene_plan.h"
#include "builtin/terrain.h"

namespace ferry::builtin {

using ElementMeshes = std::map<std::string, std::vector<int32_t>>;

// The ground heightfield over `grid`, cut into tiles x tiles square meshes
// (grid.segments must be a multiple of tiles); tiles wholly in the deep sea,
// where the seabed plane lies just below, are left out. uvs span the whole
// grid, so every tile shares one ground texture.
void addGroundTiles(ScenePlan& plan, const Shape& shape, const TerrainGrid& grid, int tiles,
                    int32_t material, ElementMeshes& out);

// Peak k as an apex cap and `sectors` sectors around it, rings x segments
// cells in all (segments a multiple of sectors), textured by the ground's uvs.
void addPeak(ScenePlan& plan, const Shape& shape, int k, const TerrainGrid& grid, int rings,
             int segments, int sectors, int32_t material, const std::string& element,
             ElementMeshes& out);

void addCliffs(ScenePlan& plan, const Shape& shape, int detail, int32_t material,
               ElementMeshes& out);

// The beach's sand layer in `pieces` arcs of nu / pieces x nv cells.
void addBeach(ScenePlan& plan, const Shape& shape, int nu, int nv, int pieces, int32_t material,
              ElementMeshes& out);

// Flattened rock mounds on the reef, below the surface.
void addReefMounds(ScenePlan& plan, const Shape& shape, int count, int detail, uint32_t seed,
                   int32_t material, ElementMeshes& out);

// The water surface (four quadrants) and the seabed plane out to the ocean's edge.
void addSea(ScenePlan& plan, int32_t water, int32_t seabed, ElementMeshes& out);

// The element whose ground holds the point (x, z).
std::string groundElement(const IslandShape& shape, Vec2f p);

}  // namespace ferry::builtin
