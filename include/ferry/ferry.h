// Ferry as a library: a Session renders a scene on this process alone, or on
// every rank of an application's communicator (ferry/ferry_mpi.h), and hands
// back the image as float RGBA. The scene is named (a file or builtin:NAME)
// or given from memory: meshes, instances, materials, lights, volumes, camera.
//
// Every rank of a session makes the same calls in the same order (they are
// collective). Errors are ferry::api::Error, thrown on every rank with the
// failing rank's message; the library never exits or aborts the process.
// No Embree, TBB or MPI type appears here. docs/library.md has the guide.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#define FERRY_API __attribute__((visibility("default")))

namespace ferry::api {

class FERRY_API Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How a mesh's arrays are held: copied into the session, or borrowed
// (nothing is copied: the caller keeps them alive and unchanged until the
// session ends, or hands MeshData::keepAlive an owner of them).
enum class Arrays { Copy, Borrow };

using Vec3 = std::array<float, 3>;
// A placement, row-major 3x4 (rotation and scale, then translation per row).
using Transform = std::array<float, 12>;
inline constexpr Transform kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

struct MeshData {
  std::string name;
  std::span<const float> positions;   // x, y, z per vertex
  std::span<const uint32_t> indices;  // three per triangle
  std::span<const float> normals;     // empty, or x, y, z per vertex
  std::span<const float> uvs;         // empty, or u, v per vertex
  int material = 0;                   // from addMaterial (0: the default grey)
  Arrays arrays = Arrays::Copy;
  // Borrowed: held by the session as long as it uses the arrays (may be null).
  std::shared_ptr<const void> keepAlive;
  // Borrowed: the 4 bytes after the last position are readable (Embree
  // reads 16 bytes at the last vertex); else the tracer keeps a padded
  // copy of the positions (only).
  bool readablePastEnd = false;
};

// Curves (fur, hair, grass; pbrt's "curve", Embree's curve geometries):
// cubic Bézier segments, each the 4 consecutive control points from its
// index (strands of k segments share end points: 3k + 1 points), with a
// width at every control point (a segment's ends' widths are used) or one
// width for all. type: "flat" (a ribbon facing the ray), "cylinder" (the
// same, shaded as a tube) or "ribbon" (turned by a normal at each control
// point, as the widths). Copied into Ferry's own layout.
struct CurvesData {
  std::string name;
  std::span<const float> points;      // x, y, z per control point
  std::span<const uint32_t> indices;  // a segment's first control point
  std::span<const float> widths;      // one per control point, or a single one
  std::span<const float> normals;     // ribbons: x, y, z per control point
  std::string type = "flat";
  int material = 0;
};

// A surface's material. type: "diffuse" (color), "conductor" (a metal: color
// at normal incidence, roughness), "dielectric" (glass: ior, roughness,
// color as tint), "principled" (glTF's metallic-roughness: color, metallic,
// roughness). Any type emits `emission` (radiance) from both sides.
struct MaterialData {
  std::string name;
  std::string type = "diffuse";
  Vec3 color{0.8f, 0.8f, 0.8f};
  Vec3 emission{0, 0, 0};
  float roughness = 0;
  float metallic = 0;
  float ior = 1.5f;
};

// A grid of densities (copied) over a world box (x fastest, then y, then z), as
// smoke (sigma_a and sigma_s per unit density and length, Henyey-Greenstein
// g), or drawn through a colour map (values in [0, 1]; opacity scales it).
struct VolumeData {
  std::string name;
  std::array<int, 3> dims{0, 0, 0};
  std::span<const float> values;
  Vec3 lower{0, 0, 0}, upper{1, 1, 1};
  Vec3 sigmaA{1, 1, 1}, sigmaS{9, 9, 9};
  float g = 0;
  std::string colorMap;  // empty: smoke; else cool-to-warm, viridis, inferno, black-body, grayscale
  float opacity = 1;
};

struct Camera {
  Vec3 from{0, 0, 5}, at{0, 0, 0}, up{0, 1, 0};
  float fovY = 45;  // degrees
  // A thin lens: rays leave a disk of this radius around `from` and meet on
  // the plane focalDistance ahead along the view axis (0: a pinhole).
  float lensRadius = 0;
  float focalDistance = 1e6f;
};

// Whose data a rank gives. Replicated: every rank gives the whole scene (the
// same calls) and Ferry partitions it over the ranks. Distributed: each rank
// gives only its own piece (as a simulation holds it); the proxies and
// lights are exchanged, nothing is partitioned or moved (docs/library.md).
enum class Distribution { Replicated, Distributed };

// How far a session's work has come (Options::progress, on rank 0).
struct Progress {
  std::string stage;  // "load" (reading and spreading the scene) or "render"
  // load: of the file or part `what`, in its reader's units; render: samples
  // per pixel done, over every frame of the render() call.
  uint64_t done = 0, total = 0;
  // load: what is being read; when finished, the set-up's intervals in
  // seconds ("load 1.20, build 0.40").
  std::string what;
  int frame = 0;            // render: the frame being rendered (0-based)
  double secondsLeft = -1;  // render: estimated; -1 while unknown
  bool finished = false;    // the stage is over
};

struct Options {
  int width = 0, height = 0;  // 0: the scene's own (pbrt's Film), else 1280 x 720
  int samplesPerPixel = 1;    // per frame
  int maxDepth = -1;          // -1: the scene's own (pbrt's Integrator), else 5
  uint32_t seed = 1;
  int threads = 0;  // per rank; 0: all cores, shared out when ranks share a machine (--threads)
  Distribution distribution = Distribution::Replicated;
  // Replicated: the partitioner (empty: "best" on many ranks).
  std::string partitioner;
  bool imageOnEveryRank = false;  // else the image is on rank 0 only
  // Every other setting of `ferry render`, by its flag's name without the
  // dashes, with the value as the flag takes it: {"forwarding", "ring"},
  // {"crop", "0,0.5,0,1"}, {"checkpoint", "run.ckpt"} (docs/library.md
  // lists them). Not those with a field above (size, spp, max-depth, seed,
  // threads, partitioner) nor the command's own (frames, output, stats,
  // quiet, show-partition). An unknown name or a bad value is an Error.
  std::map<std::string, std::string> settings;
  // Called on rank 0 as the scene loads and renders (may be empty).
  std::function<void(const Progress&)> progress;
};

// An AOV (arbitrary output variable) a render wrote beside the colour, when
// asked with the setting {"aov", "albedo,normal,depth"}: a feature of the
// surface each camera ray met first, averaged over the pixel's samples like
// the colour (docs/guide.md, "AOVs": albedo, normal, geometric-normal,
// depth, position, uv).
struct Aov {
  std::string name;                       // "albedo"
  std::vector<std::string> channelNames;  // as in an EXR: "Albedo.R", "Albedo.G", "Albedo.B"
  std::vector<float> values;              // channels() floats a pixel, row 0 at the top;
                                          // empty where the image is (Image::empty())
  int channels() const { return int(channelNames.size()); }
};

// Linear radiance, RGBA (alpha 1), row 0 at the top; empty off rank 0
// unless Options::imageOnEveryRank. With AOVs, those too (in the order asked).
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;
  std::vector<Aov> aovs;
  bool empty() const { return rgba.empty(); }
  // The AOV named `name`, or null.
  const Aov* aov(const std::string& name) const {
    for (const Aov& a : aovs)
      if (a.name == name) return &a;
    return nullptr;
  }
};

// An array of the VTK data a scene was read from (Session::fields).
struct Field {
  std::string name;
  bool atCells = false;   // a cell array, else a point array
  int components = 1;     // more than 1: rendered by its magnitude
  double lo = 0, hi = 0;  // its range (of the magnitude)
  bool shown = false;     // the array the volumes render
};

// What the last render() counted, summed over ranks.
struct Stats {
  uint64_t raysTraced = 0;     // closest-hit and shadow rays
  uint64_t raysForwarded = 0;  // sent to another rank
  double seconds = 0;          // the render's wall time (slowest rank)
  // Bytes of mesh arrays the ranks hold: copies they own, and borrowed
  // arrays they read in place (Arrays::Borrow; shared part files).
  uint64_t meshBytesOwned = 0;
  uint64_t meshBytesBorrowed = 0;
  std::string json;  // everything, as `ferry render --stats` writes it
  // Rank 0: the table `ferry render` prints (counters, memory per rank,
  // time to first pixel, compositing).
  std::string summary;
};

struct SessionAccess;  // the library's own way in (src/api/session_on.h)

class FERRY_API Session {
 public:
  // This process alone.
  explicit Session(const Options& options = {});
  // The ranks of an application's communicator, by its Fortran handle
  // (MPI_Comm_c2f; mpi4py's Comm.py2f()): ferry/ferry_mpi.h takes an MPI_Comm.
  Session(int fortranCommunicator, const Options& options);
  ~Session();
  Session(Session&&) noexcept;
  Session& operator=(Session&&) noexcept;

  int rank() const;
  int size() const;

  // The scene by name, instead of what was added: a file (.pbrt, .obj,
  // .ply, .gltf, .glb, .vdb, raw:...) or builtin:NAME[?...]. Collective.
  void load(const std::string& scene);

  // A scene from memory; indices returned are this rank's, from 0.
  int addMaterial(const MaterialData& material);
  // A mesh, not placed: put it in objects with addObject.
  int addMesh(const MeshData& mesh);
  // A group of meshes placed together by instances.
  int addObject(std::span<const int> meshes);
  void addInstance(int object, const Transform& transform = kIdentity);
  // A mesh placed once, untransformed (addMesh, addObject, addInstance).
  int placeMesh(const MeshData& mesh);
  void addVolume(const VolumeData& volume);
  // Curves placed once, untransformed (their own object and instance).
  void placeCurves(const CurvesData& curves);
  // Lights: a sun (towards it; irradiance in W/m^2) and a constant sky.
  void addSun(const Vec3& direction, const Vec3& irradiance);
  void setEnvironment(const Vec3& color);

  // Between renders, without reloading.
  void setCamera(const Camera& camera);
  void setImageSize(int width, int height);
  void setSamplesPerPixel(int samples);
  // Restyles the volumes drawn through a colour map (whole or in bricks
  // over the ranks): `colorMap` one of Ferry's maps ("viridis", ...; ""
  // each volume's own), `opacity` a scale of their extinction (1: as
  // loaded). Between renders, without reloading; an Error for an unknown map.
  void setVolumeLook(const std::string& colorMap, float opacity = 1);

  // Loads and spreads the scene now (else the next render does): errors in
  // it surface here. Collective.
  void prepare();
  // After prepare() or render(): the image file the scene names for itself
  // (pbrt's Film "filename"), or empty.
  std::string filmFilename() const;
  // After prepare() or render(): the arrays of the VTK data the scene was
  // read from (.vti, .vtu, .vts, .pvtu), each with its range; empty for any
  // other scene.
  std::vector<Field> fields() const;
  // Renders the array `name` of that data from the next render on (the data
  // is read again; before the first, the setting "field"). An Error naming
  // the arrays if the loaded data has none by that name.
  void setField(const std::string& name);

  // Renders `frames` frames, accumulated. Collective.
  Image render(int frames = 1);
  const Stats& stats() const;

 private:
  friend struct SessionAccess;
  struct Impl;
  explicit Session(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Writes `image` to `path`: .png (tone mapped as `ferry render` does, with
// `exposure` in stops), .exr or .pfm (linear). Written whole or not at all.
// Its AOVs go into an .exr as float channels (Albedo.R, ...), and beside a
// .pfm as files (out.pfm: out.albedo.pfm; 1 or 3 channels, uv as u, v, 0);
// a .png cannot hold them (an Error: clear image.aovs to write the colour).
FERRY_API void writeImage(const std::string& path, const Image& image, float exposure = 0);
// Where writeImage puts AOV `aov` of a .pfm `path`: "out.pfm" -> "out.albedo.pfm".
FERRY_API std::string aovFilePath(const std::string& path, const std::string& aov);

// One call: `scene` rendered on this process alone.
FERRY_API Image render(const std::string& scene, const Options& options = {}, int frames = 1);

}  // namespace ferry::api
