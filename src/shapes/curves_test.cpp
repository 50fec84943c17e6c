// Curves (shapes/curves.h) through every stage of the shape seam: pbrt's
// crossings (widths, ends, the nearest of several, ribbons narrowing when
// seen edge-on), the surface frame hair shading reads, both trace backends,
// part files, partitioning (a large curve set is cut into pieces that spread
// over ranks) and the distributed image (the same on 1 and 3 ranks).
#include "shapes/curves.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "builtin/builtin.h"
#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "io/parts/part_file.h"
#include "partition/partitioner.h"
#include "partition/scene_split.h"
#include "render/render_test_util.h"
#include "scene/memory_cost.h"
#include "session/render_session.h"
#include "session/session_test_util.h"
#include "shapes/shape_kinds.h"
#include "trace/embree_backend.h"
#include "trace/reference_backend.h"

namespace ferry {
namespace {

using namespace ferry::testing;
namespace fs = std::filesystem;

// A straight segment along x from 0 to 3 at y = z = 0, `w` wide.
CurveSegment straight(float w0, float w1) {
  CurveSegment s;
  s.points = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(2, 0, 0), Vec3f(3, 0, 0)};
  s.width0 = w0;
  s.width1 = w1;
  return s;
}

TEST(Curves, AFlatCurveIsCrossedWithinItsWidthAndFacesTheRay) {
  const Curves c(CurveType::Flat, {straight(0.2f, 0.2f)});
  float t;
  Vec2f uv;
  // Straight down onto it: t is the height, u along, v across.
  ASSERT_TRUE(c.intersect(0, {1.5f, 0.05f, 5}, {0, 0, -1}, 0, kInfinity, t, uv));
  EXPECT_NEAR(t, 5, 1e-4f);
  EXPECT_NEAR(uv.x, 0.5f, 1e-3f);
  EXPECT_NEAR(std::abs(uv.y), 0.5f, 1e-3f);  // 0.05 off the axis of a 0.2 ribbon
  // Outside the width, past the ends, beyond tfar or before tnear: no crossing.
  EXPECT_FALSE(c.intersect(0, {1.5f, 0.11f, 5}, {0, 0, -1}, 0, kInfinity, t, uv));
  EXPECT_FALSE(c.intersect(0, {3.2f, 0, 5}, {0, 0, -1}, 0, kInfinity, t, uv));
  EXPECT_FALSE(c.intersect(0, {1.5f, 0, 5}, {0, 0, -1}, 0, 4.9f, t, uv));
  EXPECT_FALSE(c.intersect(0, {1.5f, 0, 5}, {0, 0, -1}, 5.1f, kInfinity, t, uv));
  // From the side (along y): the ribbon turns to face that ray too.
  ASSERT_TRUE(c.intersect(0, {1, -4, 0.05f}, {0, 2, 0}, 0, kInfinity, t, uv));
  EXPECT_NEAR(t, 2, 1e-4f);
  // The surface seen along the ray: the normal is along it, the tangent along x.
  const ShapeSurface s = c.surface(0, uv, {0, 1, 0});
  EXPECT_NEAR(std::abs(s.geometricNormal.y), 1, 1e-4f);
  EXPECT_NEAR(s.tangent.x, 3, 1e-4f);  // dp/du over the whole curve
  EXPECT_NEAR(s.position.x, 1, 1e-3f);
  EXPECT_NEAR(s.position.z, 0.05f, 1e-3f);
  EXPECT_NEAR(s.originOffset, 0.4f, 1e-5f);
}

TEST(Curves, TheWidthTapersAndTheNearestOfTwoCrossingsIsFound) {
  const Curves tapered(CurveType::Flat, {straight(0.4f, 0)});
  float t;
  Vec2f uv;
  EXPECT_TRUE(tapered.intersect(0, {0.3f, 0.15f, 5}, {0, 0, -1}, 0, kInfinity, t, uv));
  EXPECT_FALSE(tapered.intersect(0, {2.7f, 0.15f, 5}, {0, 0, -1}, 0, kInfinity, t, uv));
  // A U-turn seen from its open side along x: two arms, the nearer one wins.
  CurveSegment u;
  u.points = {Vec3f(0, 0, 0), Vec3f(0, 0, 4), Vec3f(0, 2, 4), Vec3f(0, 2, 0)};
  u.width0 = u.width1 = 0.1f;
  const Curves loop(CurveType::Flat, {u});
  ASSERT_TRUE(loop.intersect(0, {0, 1, -10}, {0, 0, 1}, 0, kInfinity, t, uv));
  EXPECT_GT(t, 12);  // the top of the U, about z = 3
  // Across both arms at z = 1, from either side: the arm on that side.
  ASSERT_TRUE(loop.intersect(0, {0, -10, 1}, {0, 1, 0}, 0, kInfinity, t, uv));
  EXPECT_LT(t, 10.5f);  // the arm near y = 0
  EXPECT_LT(uv.x, 0.5f);
  ASSERT_TRUE(loop.intersect(0, {0, 12, 1}, {0, -1, 0}, 0, kInfinity, t, uv));
  EXPECT_LT(t, 10.5f);  // the arm near y = 2
  EXPECT_GT(uv.x, 0.5f);
}

TEST(Curves, ARibbonNarrowsSeenEdgeOnAndACylinderShadesAsATube) {
  const Curves ribbon(CurveType::Ribbon, {straight(0.2f, 0.2f)},
                      {CurveNormals{Vec3f(0, 0, 1), Vec3f(0, 0, 1)}});
  float t;
  Vec2f uv;
  EXPECT_TRUE(ribbon.intersect(0, {1.5f, 0.09f, 5}, {0, 0, -1}, 0, kInfinity, t, uv));
  // Seen at 60 degrees from its normal it looks half as wide, and is crossed
  // where the ribbon itself is (through its plane within 0.1 of the axis).
  const Vec3f slanted = normalize(Vec3f(0, std::sin(1.0472f), -std::cos(1.0472f)));
  EXPECT_TRUE(
      ribbon.intersect(0, Vec3f(1.5f, 0.09f, 0) - slanted * 5, slanted, 0, kInfinity, t, uv));
  EXPECT_NEAR(t, 5, 0.1f);  // (pbrt's depth: the axis's nearest point, not the plane's)
  EXPECT_FALSE(
      ribbon.intersect(0, Vec3f(1.5f, 0.11f, 0) - slanted * 5, slanted, 0, kInfinity, t, uv));
  const Curves tube(CurveType::Cylinder, {straight(0.2f, 0.2f)});
  const ShapeSurface centre = tube.surface(0, {0.5f, 0.0f}, {0, 0, -1});
  const ShapeSurface edge = tube.surface(0, {0.5f, 0.96f}, {0, 0, -1});
  EXPECT_NEAR(std::abs(centre.geometricNormal.z), 1, 1e-4f);
  EXPECT_LT(std::abs(edge.geometricNormal.z), 0.1f);
}

TEST(Curves, BadInputIsAnError) {
  EXPECT_THROW(Curves(CurveType::Flat, {straight(0, 0)}), InputError);
  EXPECT_THROW(Curves(CurveType::Flat, {straight(-1, 1)}), InputError);
  EXPECT_THROW(Curves(CurveType::Ribbon, {straight(1, 1)}), InputError);
  CurveSegment nan = straight(1, 1);
  nan.points[2].y = std::nanf("");
  EXPECT_THROW(Curves(CurveType::Flat, {nan}), InputError);
}

// Whichever rule crosses it (Embree's for flat and cylinder segments,
// pbrt's for ribbons), the surface at a crossing's (u, v) is where the ray
// met the curve: within the width, on the ray's side of the axis it crossed.
TEST(Curves, TheSurfaceAtACrossingIsWhereTheRayMetTheCurve) {
  TestRng rng(5);
  int crossings = 0;
  for (CurveType type : {CurveType::Flat, CurveType::Cylinder, CurveType::Ribbon}) {
    for (int k = 0; k < 40; ++k) {
      // A gently bent segment (as pbrt's splitting leaves them) along a random line.
      CurveSegment s;
      const Vec3f along =
          normalize(Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f));
      for (int j = 0; j < 4; ++j)
        s.points[j] =
            along * float(j) +
            Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * 0.1f;
      s.width0 = 0.1f + 0.2f * rng.uniform();
      s.width1 = 0.1f + 0.2f * rng.uniform();
      s.u0 = 0.25f;
      s.u1 = 0.5f;
      std::vector<CurveNormals> normals;
      if (type == CurveType::Ribbon) normals.push_back({Vec3f(0, 0, 1), Vec3f(0, 1, 0)});
      const Curves curves(type, {s}, normals);
      for (int r = 0; r < 100; ++r) {
        const Vec3f target =
            along * (3 * rng.uniform()) +
            Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * 0.4f;
        const Vec3f direction =
            normalize(Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f));
        const Vec3f origin = target - direction * 10.0f;
        float t;
        Vec2f uv;
        if (!curves.intersect(0, origin, direction, 0, kInfinity, t, uv)) continue;
        ++crossings;
        EXPECT_GE(uv.x, 0.0f);
        EXPECT_LE(uv.x, 1.0f);
        EXPECT_GE(uv.y, -1.0f);
        EXPECT_LE(uv.y, 1.0f);
        const ShapeSurface at = curves.surface(0, uv, direction);
        EXPECT_GE(at.uv.x, s.u0);
        EXPECT_LE(at.uv.x, s.u1);
        // Seen along the ray, the surface point lies on the hit's side of the
        // axis; for a ribbon facing the ray it is the hit, within a sixth of
        // the width and the pieces' bend (they are straight, the curve is not).
        const Vec3f hit = origin + direction * t;
        const Vec3f axis = curves.surface(0, {uv.x, 0.0f}, direction).position;
        const auto seen = [&](Vec3f v) { return v - direction * dot(v, direction); };
        const float w = std::max(s.width0, s.width1);
        const Vec3f toSurface = seen(at.position - axis), toHit = seen(hit - axis);
        // (Not opposite: a ribbon seen nearly edge-on shows little of either.)
        if (length(toSurface) > 0.05f * w && length(toHit) > 0.05f * w) {
          EXPECT_GT(dot(normalize(toSurface), normalize(toHit)), -0.7f) << int(type) << " " << k;
        }
        if (type == CurveType::Ribbon) continue;
        EXPECT_LT(length(seen(at.position - hit)), 0.15f * w + 0.02f)
            << int(type) << " " << k << " v " << uv.y;
      }
    }
  }
  EXPECT_GT(crossings, 200);
}

const Communicator& oneRank() {
  static InProcessGroup group(1);
  return group.communicator(0);
}

// Embree bounds and tests each ribbon segment in pieces (Shape::pieceBounds);
// the nearest of the pieces' crossings must be the whole segment's, bit for
// bit, and lie in the box of the piece that found it.
TEST(Curves, ThePiecesOfASegmentAnswerAsTheWholeSegment) {
  TestRng rng(11);
  int crossings = 0;
  for (CurveType type : {CurveType::Ribbon}) {
    for (int k = 0; k < 120; ++k) {
      CurveSegment s;
      for (Vec3f& p : s.points) p = Vec3f(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0f;
      s.width0 = 0.02f + 0.3f * rng.uniform();
      s.width1 = 0.3f * rng.uniform();
      std::vector<CurveNormals> normals;
      if (type == CurveType::Ribbon) normals.push_back({Vec3f(0, 0, 1), Vec3f(1, 0, 0)});
      const Curves curves(type, {s}, normals);
      ASSERT_EQ(curves.piecesPerPrimitive(), Curves::kTraversalPieces);
      for (int r = 0; r < 200; ++r) {
        // Aimed at a point near the curve, from anywhere around it.
        const float u = rng.uniform();
        const Vec3f target =
            s.points[0] * ((1 - u) * (1 - u) * (1 - u)) +
            s.points[1] * (3 * u * (1 - u) * (1 - u)) + s.points[2] * (3 * u * u * (1 - u)) +
            s.points[3] * (u * u * u) +
            Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * 0.3f;
        const Vec3f origin = target + normalize(Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f,
                                                      rng.uniform() - 0.5f)) *
                                          10.0f;
        const Vec3f direction = (target - origin) * 0.37f;
        float t = 0;
        Vec2f uv;
        const bool whole = curves.intersect(0, origin, direction, 0, 1e30f, t, uv);
        // Embree's way: the pieces in some order, each under the nearest so far.
        float tfar = 1e30f, tp = 0;
        Vec2f uvp;
        bool found = false;
        ShapeWork work;
        const uint32_t pieces = curves.piecesPerPrimitive();
        for (uint32_t i = 0; i < pieces; ++i) {
          const uint32_t j = pieces - 1 - i;  // last first, not the order test() takes
          float tj;
          Vec2f uvj;
          if (!curves.intersectPiece(0, j, origin, direction, 0, tfar, tj, uvj, work)) continue;
          // In the box of the piece its u lies in (either, on a boundary).
          const Vec3f hit = origin + direction * tj;
          const float at = uvj.x * float(pieces);
          const auto below = uint32_t(std::clamp(std::ceil(at) - 1, 0.0f, float(pieces - 1)));
          const auto above = uint32_t(std::clamp(std::floor(at), 0.0f, float(pieces - 1)));
          EXPECT_TRUE(curves.pieceBounds(0, below).contains(Box3f{hit, hit}) ||
                      curves.pieceBounds(0, above).contains(Box3f{hit, hit}))
              << k << " " << r;
          found = true;
          tfar = tp = tj;
          uvp = uvj;
        }
        ASSERT_EQ(found, whole) << int(type) << " " << k << " " << r;
        if (!whole) continue;
        ++crossings;
        EXPECT_EQ(tp, t);
        EXPECT_EQ(uvp.x, uv.x);
        EXPECT_EQ(uvp.y, uv.y);
      }
    }
  }
  EXPECT_GT(crossings, 2000);
}

TEST(Curves, BothBackendsFindTheSameFibres) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:fur?strands=2000"));
  const auto embree = makeEmbreeBackend(scene), reference = makeReferenceBackend(scene);
  const CameraView& view = scene.views[0];
  TestRng rng(3);
  int fibreHits = 0;
  for (int k = 0; k < 3000; ++k) {
    TraceRay ray;
    ray.origin = view.from;
    const Vec3f target =
        view.at + Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) *
                      (2.4f * length(view.at - view.from) / 5.5f);
    ray.direction = normalize(target - ray.origin);
    const TraceHit a = embree->intersect(ray), b = reference->intersect(ray);
    ASSERT_EQ(a.valid(), b.valid()) << k;
    if (!a.valid()) continue;
    EXPECT_NEAR(a.t, b.t, 1e-5f * a.t) << k;
    if (a.instance != b.instance || a.slot != b.slot) continue;
    EXPECT_EQ(a.primitive, b.primitive) << k;
    // (The backends move the ray into the instance's space each its own way.)
    EXPECT_NEAR(a.u, b.u, 1e-4f) << k;
    EXPECT_NEAR(a.v, b.v, 3e-4f) << k;  // (-1 to 1 across)
    const Object& o = scene.objects[scene.instances[a.instance].object];
    fibreHits += size_t(a.slot) >= o.meshes.size();
    EXPECT_EQ(embree->occluded(ray), reference->occluded(ray));
  }
  EXPECT_GT(fibreHits, 300);
}

TEST(Curves, APartFileStoresThemAndTheMemoryModelCountsThem) {
  const Curves ribbon(CurveType::Ribbon, {straight(0.2f, 0.1f)},
                      {CurveNormals{Vec3f(0, 0, 1), Vec3f(0, 1, 0)}});
  EXPECT_EQ(ribbon.bytes(), sizeof(CurveSegment) + sizeof(CurveNormals));
  Scene scene;
  const int32_t m = scene.addMaterial(diffuseMaterial(Vec3f(0.5f)));
  scene.addSingleInstanceGeometry({"ribbon", m, std::make_shared<Curves>(ribbon)});
  const MemoryCost cost = geometryCost(scene.geometries[0]);
  EXPECT_EQ(cost.shapes, ribbon.bytes());
  const fs::path path = fs::temp_directory_path() / fmt::format("ferry-curves-{}.part", ::getpid());
  writePartFile(path.string(), scene, {0}, {RankSet::single(0)}, 0, 1);
  const LoadedPart part = readPartFile(path.string());
  fs::remove(path);
  ASSERT_EQ(part.scene.geometries.size(), 1u);
  const auto* back = dynamic_cast<const Curves*>(part.scene.geometries[0].shape.get());
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->type(), CurveType::Ribbon);
  ASSERT_EQ(back->segments().size(), 1u);
  EXPECT_EQ(back->segments()[0].points[3], Vec3f(3, 0, 0));
  EXPECT_EQ(back->normals()[0][1], Vec3f(0, 1, 0));
  ASSERT_NE(shapeKind("curves"), nullptr);
}

TEST(Curves, ALargeCurveSetIsCutIntoPiecesThatKeepEverySegment) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:fur?strands=4000"));
  const uint64_t segments = 4000 * 4;
  SceneSplitOptions options;
  options.maxPieceBytes = segments * sizeof(CurveSegment) / 6;
  const SceneSplitReport report = splitForPartitioning(scene, options);
  uint64_t total = 0, pieces = 0;
  for (const Geometry& g : scene.geometries)
    if (dynamic_cast<const Curves*>(g.shape.get())) {
      total += g.shape->primitiveCount();
      ++pieces;
    }
  EXPECT_EQ(total, segments);
  EXPECT_GE(pieces, 6u);
  EXPECT_GE(report.piecesMade, pieces);
  scene.validate();
}

TEST(Curves, TheImageIsTheSameOnOneAndThreeRanks) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:fur?strands=3000"));
  SessionSettings settings;
  settings.render.width = 48;
  settings.render.height = 32;
  settings.render.samplesPerPixel = 2;
  settings.render.maxDepth = 4;
  settings.render.frames = 1;
  const std::vector<Vec3f> one = renderLinear(scene, settings, oneRank());
  ASSERT_FALSE(one.empty());
  for (const Partitioner* partitioner : std::initializer_list<const Partitioner*>{
           &bestPartitioner(), &partitionerNamed("round-robin")}) {
    std::vector<Vec3f> three;
    runRanks(3, [&](const Communicator& comm) {
      SessionSettings s = settings;
      s.partitioner = partitioner;
      std::vector<Vec3f> image = renderLinear(scene, s, comm);
      if (comm.isRoot()) three = std::move(image);
    });
    EXPECT_TRUE(three == one) << partitioner->name();
  }
}

}  // namespace
}  // namespace ferry
