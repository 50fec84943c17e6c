// Procedural plants and rocks for the built-in scenes. Each generator returns
// a design: the parts of one object (trunk, leaves, ...), each with the role
// that picks its material, its exact counts from the parameters, and a
// function that makes the mesh. Random numbers shape the geometry but never
// its topology, so counts are known without making anything.
//
// Conventions: y is up, the plant stands at the origin with its base at
// y = 0 (slightly below, so it does not float on slopes), units are metres.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "builtin/shapes.h"
#include "scene/scene.h"

namespace ferry::builtin {

// Which material a part gets; the scene maps roles to its materials.
enum class PartRole : uint8_t {
  Wood,
  Leaves,
  Fronds,
  Fruit,
  Blades,
  Stems,
  Petals,
  FlowerCentre,
  Rock
};

struct PlantPart {
  std::string name;  // "trunk", "leaves", ...
  PartRole role = PartRole::Wood;
  MeshCounts counts;
  bool hasNormals = true;
  bool hasUvs = true;
  std::function<Mesh()> build;
  // Which of several meshes of one role this is (a tree's leaf meshes, a
  // patch's groups of clumps): scenes may vary the material by it.
  int group = 0;
};
using PlantDesign = std::vector<PlantPart>;

MeshCounts designCounts(const PlantDesign& design);

// One level of branching below the trunk (or below the previous level).
struct BranchLevel {
  int children = 4;  // per parent branch
  int rings = 6;     // cross-sections along each branch
  int sides = 6;
  float lengthRatio = 0.5f;    // child length / parent length
  float radiusRatio = 0.5f;    // child base radius / parent radius where it attaches
  float spreadDegrees = 45;    // angle from the parent's direction
  float startFraction = 0.3f;  // children attach over [start, 1] of the parent
  float gravity = 0.0f;        // > 0 bends towards the sky, < 0 droops
  float taper = 0.35f;         // tip radius / base radius
};

// Broadleaf trees, bushes, conifers and the banyan (with aerial roots).
struct TreeParams {
  float trunkLength = 8;
  float trunkRadius = 0.3f;
  int trunkRings = 16;
  int trunkSides = 10;
  float trunkTaper = 0.45f;
  float trunkLean = 0.15f;  // sideways drift of the trunk top, as a fraction of its length
  float trunkFlare = 0.6f;  // extra radius at the foot
  std::vector<BranchLevel> levels;
  float coneFactor = 0;   // > 0: branches near the top are shorter (conifers)
  int leavesPerTip = 20;  // leaf cards on each branch of the last level
  int leafSegments = 2;   // each card is bent along its length
  float leafSize = 0.6f;
  float leafSpread = 0.7f;  // leaves cover this fraction of a tip branch, from its end
  float leafDroop = 0.25f;
  int aerialRoots = 0;  // banyan: roots hanging from the first branch level
  int rootRings = 16;
  int rootSides = 6;
  float rootRadius = 0.06f;
  // How the tree is cut into meshes, as production plant models are (one
  // mesh per branch level and several leaf meshes): the wood in one mesh per
  // level ("trunk", "branches-1", ...) or one "wood" mesh; the leaves in
  // `leafMeshes` meshes ("leaves-0", ...; "leaves" when 1), each the leaves
  // of a run of tip branches. The geometry is the same either way.
  bool woodByLevel = false;
  int leafMeshes = 1;
};
MeshCounts treeWoodCounts(const TreeParams& p);
PlantDesign designTree(const TreeParams& p, uint32_t seed);

struct PalmParams {
  float height = 9;
  float trunkRadius = 0.17f;
  int trunkRings = 40;
  int trunkSides = 12;
  float lean = 0.25f;  // top offset as a fraction of the height
  int fronds = 16;
  int frondSegments = 16;
  float frondLength = 3.6f;
  float frondWidth = 1.2f;
  int coconuts = 6;
  int coconutDetail = 3;
};
PlantDesign designPalm(const PalmParams& p, uint32_t seed);

struct FernParams {
  int fronds = 18;
  int segments = 16;
  float length = 1.1f;
  float width = 0.4f;
};
PlantDesign designFern(const FernParams& p, uint32_t seed);

struct GrassParams {
  int blades = 128;
  int segments = 5;
  float height = 0.6f;
  float radius = 0.25f;
  float width = 0.018f;
};
PlantDesign designGrass(const GrassParams& p, uint32_t seed);

struct FlowerParams {
  int stems = 12;
  int stemRings = 6;
  int stemSides = 4;
  float height = 0.45f;
  float spread = 0.15f;
  int leavesPerStem = 3;
  int petals = 6;
  float petalLength = 0.05f;
  int centreDetail = 2;
  float centreRadius = 0.012f;
};
PlantDesign designFlowers(const FlowerParams& p, uint32_t seed);

// A patch of ground cover as one object: `clumps` small plants spread over a
// disc, as scattering tools bake a meadow tile. Clump k is `clump(k)` (every
// clump with the same parts in the same order), turned and scaled at a spot
// that is a pure function of (seed, k). The clumps are cut into `groups`
// runs; each part of each run is one mesh, named "<group>/<part>", with
// PlantPart::group set.
struct PatchParams {
  float radius = 4;  // clump centres lie in this disc around the origin
  int clumps = 100;
  int groups = 4;
  float scaleMin = 0.75f, scaleMax = 1.25f;
};
PlantDesign designPatch(const PatchParams& p, const std::function<PlantDesign(int clump)>& clump,
                        uint32_t seed);

struct RockParams {
  int detail = 16;  // cube-sphere cells per face edge
  Vec3f radii{1, 0.7f, 1};
  float roughness = 0.3f;  // the radius varies within [1 - r, 1 + r]
  float frequency = 1.4f;
  int octaves = 4;
  float sink = 0.25f;  // fraction of radii.y below y = 0
};
// Every vertex lies within radii * (1 + roughness) of the centre, which sits
// at y = radii.y * (1 - sink): a bound the scenes use for exact extents.
PlantDesign designRock(const RockParams& p, uint32_t seed);
Vec3f rockSurface(const RockParams& p, uint32_t seed, Vec3f direction);

struct LogParams {
  float length = 3;
  float radius = 0.15f;
  int rings = 40;
  int sides = 12;
  int stubs = 4;
  int stubRings = 8;
  int stubSides = 6;
};
PlantDesign designLog(const LogParams& p, uint32_t seed);

}  // namespace ferry::builtin
