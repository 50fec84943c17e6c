// The scene model: what every loader and generator produces and every
// renderer, partitioner and part file consumes.
//
// Geometry is two-level: meshes are grouped into objects, and objects are
// placed by instances. A non-instanced mesh is an object with one instance
// (identity transform). Instancing is never flattened, because scenes like the
// island are only representable that way.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/shared_array.h"
#include "material/fourier_bsdf_table.h"
#include "material/material_model.h"
#include "media/medium.h"
#include "scene/motion.h"
#include "scene/shape.h"
#include "scene/texture.h"

namespace ferry {

constexpr int32_t kNoTexture = -1;

// How a cut-out's alpha makes a hole (trace/alpha_cutout.h).
enum class AlphaTest : uint8_t {
  Below,       // where alpha < the cutoff (glTF's MASK, OBJ, the built-ins)
  Zero,        // only where alpha is exactly 0 (pbrt-v3)
  Stochastic,  // with probability 1 - alpha, a hash of the ray and the hit (pbrt-v4)
};
// Which rays a cut-out lets through: pbrt-v3's "alpha" is for paths and its
// "shadowalpha" for shadow rays.
enum class AlphaRays : uint8_t { All, NotShadowRays, ShadowRaysOnly };

// A surface's material: what every surface has (colour and its texture,
// emission, cut-out, bump or normal map, mix) and how it scatters light, its
// model (material/material_model.h: diffuse, conductor, dielectric, ...).
struct Material {
  std::string name;
  // The model's colour (a diffuse albedo, a conductor's reflectance, a
  // glass's tint) times its texture.
  Vec3f baseColor{0.8f, 0.8f, 0.8f};
  int32_t baseColorTexture = kNoTexture;
  std::shared_ptr<const MaterialModel> model = defaultMaterialModel();  // never null
  Vec3f emission{0, 0, 0};  // radiance leaving the surface
  // A cut-out: where the texture's alpha passes `alphaTest` (with
  // alphaCutoff for Below), `alphaRays` go through (trace/alpha_cutout.h).
  int32_t alphaTexture = kNoTexture;
  float alphaCutoff = 0.5f;
  AlphaTest alphaTest = AlphaTest::Below;
  AlphaRays alphaRays = AlphaRays::All;
  // An emitter lights both sides of its triangles (Ferry's built-ins, OBJ,
  // glTF), or only the side its winding normal faces (pbrt's area lights
  // unless "twosided": the loader orients the winding as pbrt would).
  bool emitsBackSide = true;
  // A one-sided emitter whose light is sampled (next-event estimation,
  // light paths) leaving the side opposite the one a ray sees emitting:
  // pbrt-v3's area lights under a transform that swaps handedness
  // (docs/fidelity.md). False everywhere else.
  bool lightSampledOnBackSide = false;
  // Shading-normal perturbation (render/surface.h), in uv space: a bump map
  // (a displacement along the normal of bumpScale times the texture's grey
  // value, in world units) or a tangent-space normal map (RGB in [0, 1] ->
  // [-1, 1], x and y times normalScale; x along +u, y along +v).
  int32_t bumpTexture = kNoTexture;
  float bumpScale = 1;
  int32_t normalTexture = kNoTexture;
  float normalScale = 1;
  // pbrt's mix: at each shading point, materials[mixedWith] is used instead
  // of this one with probability mixAmount, a pure function of the pixel
  // sample; -1: not a mix. Chains are allowed, cycles are not (validate).
  int32_t mixedWith = -1;
  float mixAmount = 0;

  bool isEmissive() const { return maxComponent(emission) > 0; }
  // The tabulated BSDF its model reads (Scene::bsdfTables), or kNoBsdfTable.
  int32_t bsdfTable() const { return model->bsdfTable(); }
  // Every texture index the material holds (kNoTexture where unused), for
  // code that keeps, drops or renumbers textures with their materials.
  std::array<int32_t*, 4> textureSlots() {
    return {&baseColorTexture, &alphaTexture, &bumpTexture, &normalTexture};
  }
  std::array<int32_t, 4> textures() const {
    return {baseColorTexture, alphaTexture, bumpTexture, normalTexture};
  }
};

// Where a mesh's arrays are when they are not in memory: out-of-core
// partitioning (scene/mesh_store.h) writes them to a spill file as they are
// made and keeps this in their place, so everything that weighs or places
// meshes (costs, bounds, units, proxies) works without the arrays, and what
// needs the triangles reads them back one mesh at a time (Scene::geometry).
struct StoredMesh {
  uint64_t offset = 0;  // in the MeshStore's file
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  bool normals = false;
  bool uvs = false;
  Box3f bounds;
};

struct Mesh {
  std::string name;
  // Owned, or shared with a rank's mapped part file (core/shared_array.h).
  SharedArray<Vec3f> positions;
  SharedArray<Vec3f> normals;  // empty, or one per position
  SharedArray<Vec2f> uvs;      // empty, or one per position
  SharedArray<Vec3i> indices;  // 32-bit triangle indices into positions
  int32_t material = 0;
  // The media on its two sides (outside: where the geometric normal
  // points); no transition for most meshes.
  MediumInterface media;
  std::optional<StoredMesh> stored;  // set: the arrays above are empty and in Scene::meshStore

  uint64_t triangleCount() const { return stored ? stored->triangles : indices.size(); }
  uint64_t vertexCount() const { return stored ? stored->vertices : positions.size(); }
  bool hasNormals() const { return stored ? stored->normals : !normals.empty(); }
  bool hasUvs() const { return stored ? stored->uvs : !uvs.empty(); }
  Box3f bounds() const;
  // What is wrong with the arrays (sizes, indices, finite positions), or empty.
  std::string arrayProblem() const;
  // A trace backend may read a few bytes past the last position (Embree
  // reads 16 bytes at the last vertex): with one element of spare capacity (or
  // readable bytes after a mapped array) it shares the array, else it keeps a
  // padded copy. Loaders leave the spare element (reserveVertexSlack where
  // they finish a mesh; loadScene checks); part files always have it.
  bool hasVertexSlack() const { return positions.hasSpareElement(); }
  void reserveVertexSlack() {
    if (!positions.empty() && !hasVertexSlack()) positions.reserve(positions.size() + 1);
  }
  // Frees the arrays (or lets go of the mapping they share).
  void releaseArrays() {
    positions.clear();
    normals.clear();
    uvs.clear();
    indices.clear();
  }
};

// A shape of another kind than a triangle mesh (scene/shape.h) with its material.
struct Geometry {
  std::string name;
  int32_t material = 0;
  std::shared_ptr<const Shape> shape;  // null: released (Scene::releaseAllBut)
};

// A group of meshes and geometries placed together by instances (a tree:
// trunk + leaf cards). A hit names a slot: its meshes first, then its geometries.
struct Object {
  std::string name;
  std::vector<int32_t> meshes;      // indices into Scene::meshes
  std::vector<int32_t> geometries;  // indices into Scene::geometries
  size_t slots() const { return meshes.size() + geometries.size(); }
};

struct Instance {
  int32_t object = 0;
  Affine3f transform;  // where it is; a moving instance's start (u = 0)
  // Set when it moves while the shutter is open (scene/motion.h).
  std::shared_ptr<const InstanceMotion> motion;

  Affine3f transformAt(float u) const { return motion ? motion->at(u) : transform; }
  // The world box of `objectBox` placed here, over the whole shutter if it moves.
  Box3f placeBox(const Box3f& objectBox) const {
    return motion ? motion->sweptBox(objectBox) : transform.transformBox(objectBox);
  }
};

// Sun / directional light: radiance arriving from a small cone around `direction`.
struct SunLight {
  Vec3f direction{0, 1, 0};        // unit vector pointing *towards* the sun
  Vec3f irradiance{3, 3, 3};       // W/m^2 on a surface facing the sun
  float angularRadius = 0.00465f;  // radians (the real sun: 0.27 degrees)
};

// A point or spot light: a delta light at `position` (pbrt's point and spot
// lights). Seen from a point at distance d along unit w leaving the light, it
// gives intensity * falloff(w) / d^2; only light samples find it.
struct PointLight {
  enum class Falloff : uint8_t {
    None,        // a point light, the same in every direction
    Quartic,     // pbrt-v3's spot: ((cos - cosTotal) / (cosStart - cosTotal))^4
    SmoothStep,  // pbrt-v4's spot: smoothstep(cosTotal, cosStart, cos)
  };
  Vec3f position{0};
  Vec3f intensity{1};          // W/sr
  Vec3f direction{0, 0, 1};    // a spot's axis (unit)
  float cosTotalWidth = -1;    // a spot's edge: nothing beyond
  float cosFalloffStart = -1;  // a spot's full intensity within
  Falloff falloff = Falloff::None;

  // Of the intensity, the share leaving along unit `w`.
  float falloffTowards(Vec3f w) const {
    if (falloff == Falloff::None) return 1;
    const float c = dot(w, direction);
    if (c < cosTotalWidth) return 0;
    if (c >= cosFalloffStart) return 1;
    const float t = (c - cosTotalWidth) / (cosFalloffStart - cosTotalWidth);
    return falloff == Falloff::Quartic ? (t * t) * (t * t) : t * t * (3 - 2 * t);
  }
};

// Environment: constant colour, or an equirectangular image (y up) scaled by colour.
struct EnvironmentLight {
  Vec3f color{0, 0, 0};
  std::shared_ptr<const HdrImage> image;  // optional
  float rotation = 0;                     // radians around +y

  bool isBlack() const { return !image && maxComponent(color) <= 0; }
};

struct CameraView {
  std::string name;
  Vec3f from{0, 0, 5};
  Vec3f at{0, 0, 0};
  Vec3f up{0, 1, 0};
  float fovY = 45.0f;  // degrees
  // pbrt's cameras are left-handed: the image's right is cross(up, forward)
  // instead of cross(forward, up). Set by the pbrt loader when the camera
  // transform says so; the picture is then mirrored left to right.
  bool leftHanded = false;
  // A thin lens (pbrt's "lensradius" and "focaldistance", world units):
  // rays leave a disk of this radius around `from`, across the view axis,
  // and meet on the plane focalDistance ahead. Radius 0: a pinhole.
  float lensRadius = 0;
  float focalDistance = 1e6f;
  // A moving camera (motion blur): its world-from-camera transform over the
  // shutter (scene/motion.h); a ray at time u is the start camera's ray
  // moved by motion(u) motion(0)^-1. Null: it stays put.
  std::shared_ptr<const InstanceMotion> motion;
};

class MeshStore;

// A surface that only bounds media (pbrt's Material "" or "interface" with a
// MediumInterface): rays pass through it and change medium, nothing else
// sees it. Its mesh is in world space, outside its interface's normal side.
struct MediumBoundary {
  Mesh mesh;
  MediumInterface media;
};
// A closed box's twelve triangles, their normals pointing out of it (a
// volume's boundary, with the volume inside).
Mesh boxMesh(const Box3f& box, std::string name);

// Whether pbrt's Integrator `type` transports light from the emitters too
// (bdpt, mlt, pbrt-v4's lightpath, vcm): Ferry then adds light paths.
inline bool integratorWantsLightPaths(const std::string& type) {
  return type == "bdpt" || type == "mlt" || type == "lightpath" || type == "vcm";
}

// An array of the VTK data a volume was read from (io/volumes/vtk_file.cpp):
// any of them can be the one rendered (--field, the viewer's field choice).
struct VolumeField {
  std::string name;
  bool atCells = false;   // a cell array, else a point array
  int components = 1;     // more than 1: rendered by magnitude
  double lo = 0, hi = 0;  // its range (vectors: of the magnitude)
};

struct Scene {
  std::string name;
  std::vector<Mesh> meshes;
  std::vector<Geometry> geometries;
  std::vector<Object> objects;
  std::vector<Instance> instances;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  // Tabulated BSDFs (Material::bsdfTable()); shared, as several materials and
  // copies of the scene may name one. Released ones are null.
  std::vector<std::shared_ptr<const FourierBsdfTable>> bsdfTables;
  std::vector<SunLight> suns;
  std::vector<PointLight> pointLights;
  EnvironmentLight environment;
  std::vector<CameraView> views;  // views[0] is the default
  // Participating media (media/medium.h), the surfaces that only bound them,
  // and the medium the camera is in. Every rank holds them whole.
  std::vector<Medium> media;
  std::vector<MediumBoundary> mediumBoundaries;
  int32_t cameraMedium = kNoMedium;
  bool hasMedia() const { return !media.empty(); }
  // Whether any geometry is a volume (scene/shape.h: isVolume), a brick of one.
  bool hasVolumes() const;
  // What the scene file asks for (pbrt's Film), used when the command line
  // does not say: image size and output file name (relative to the scene file's
  // directory as written; the caller decides where to put it).
  std::optional<int> filmWidth, filmHeight;
  std::string filmFilename;
  // pbrt's Film "scale" (v3) and "iso" / 100 (v4's imaging ratio at a 1 s
  // exposure): multiplies the radiance written to the image.
  float filmScale = 1;
  // pbrt's Film "cropwindow": x0, x1, y0, y1, fractions of the image, y down
  // (render/camera.h's CropWindow); absent: the whole image.
  std::optional<std::array<float, 4>> filmCrop;
  // pbrt's Film clamp of each camera sample (render/frame_buffer.h's
  // SampleClamp): v3's "maxsampleluminance", v4's "maxcomponentvalue"; 0: none.
  float filmMaxSampleLuminance = 0, filmMaxComponentValue = 0;
  // The arrays the scene's VTK data holds, and which one its volumes render
  // (an index into them; -1: none, or not VTK data).
  std::vector<VolumeField> volumeFields;
  int32_t volumeField = -1;
  // Motion blur (scene/motion.h): the camera's shutter, and the times the
  // moving instances' start and end transforms hold (pbrt's TransformTimes).
  float shutterOpen = 0, shutterClose = 1;
  float motionStart = 0, motionEnd = 1;
  bool moves() const;  // whether any instance or view moves
  // pbrt's Integrator, as named ("bdpt", "path", ...; empty: none): a
  // bidirectional one turns light paths on (render/path_shading.h).
  std::string integrator;
  // Its "integer maxdepth", if given: the render's --max-depth when the
  // command line does not say (pbrt counts depth as Ferry does: 1 is direct
  // light only; both default to 5).
  std::optional<int> integratorMaxDepth;

  // The arrays of stored meshes (Mesh::stored); null when every mesh is in memory.
  std::shared_ptr<MeshStore> meshStore;

  // Mesh `m` with its arrays: the mesh itself, or for a stored one a copy
  // read back from meshStore into `scratch` (one mesh at a time in memory).
  const Mesh& geometry(int32_t m, Mesh& scratch) const;

  // Adds a mesh (with vertex slack) as its own object with one identity
  // instance; returns the object.
  int32_t addSingleInstanceMesh(Mesh mesh);
  // Adds a geometry of another kind as its own object with one identity
  // instance; returns the object.
  int32_t addSingleInstanceGeometry(Geometry geometry);
  int32_t addMaterial(Material material);

  Box3f objectBounds(int32_t object) const;
  Box3f worldBounds() const;
  // Finds a view by name; throws InputError listing the available ones.
  const CameraView& view(const std::string& name) const;
  // Number of instances of each object (objects placed more than once are the
  // "multi-instance" content the partitioners treat as units).
  std::vector<uint32_t> instanceCountPerObject() const;
  // Checks indices, references and numbers; throws InputError naming the element.
  // `material` and the materials it mixes with (Material::mixedWith), in
  // chain order: every material shading may use where a mesh has `material`.
  template <typename Visit>
  void forEachShadingMaterial(int32_t material, Visit&& visit) const {
    for (size_t n = 0; material >= 0 && n <= materials.size(); ++n) {
      visit(material);
      material = materials[size_t(material)].mixedWith;
    }
  }
  // Every texture those materials read.
  template <typename Visit>
  void forEachShadingTexture(int32_t material, Visit&& visit) const {
    forEachShadingMaterial(material, [&](int32_t m) {
      for (int32_t t : materials[size_t(m)].textures())
        if (t != kNoTexture) visit(t);
    });
  }
  // Every tabulated BSDF those materials use.
  template <typename Visit>
  void forEachShadingBsdfTable(int32_t material, Visit&& visit) const {
    forEachShadingMaterial(material, [&](int32_t m) {
      if (const int32_t t = materials[size_t(m)].bsdfTable(); t != kNoBsdfTable) visit(t);
    });
  }
  // What material models read besides their parameters.
  MaterialResources materialResources() const { return {bsdfTables}; }
  void validate() const;
  // Mesh::reserveVertexSlack for every mesh (a copy only where a loader left none).
  void reserveVertexSlack();
  // Frees the geometry, texels and tables no listed instance needs (a rank
  // keeps only what it owns). Indices stay valid; released meshes and
  // textures are empty, released tables null.
  void releaseAllBut(const std::vector<int32_t>& keptInstances);
};

// Whether x0, x1, y0, y1 are a crop window's fractions (Scene::filmCrop,
// render/camera.h's CropWindow): 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1.
bool isCropWindow(float x0, float x1, float y0, float y1);

}  // namespace ferry
