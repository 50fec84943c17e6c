#include "report/partition_picture.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <bit>
#include <cmath>
#include <memory>

#include "core/error.h"
#include "render/camera.h"
#include "report/canvas.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry {
namespace {

constexpr int kCheckerPixels = 6;

Rgba scaled(Rgba c, float s) {
  return {uint8_t(std::lround(c.r * s)), uint8_t(std::lround(c.g * s)),
          uint8_t(std::lround(c.b * s)), 255};
}

}  // namespace

std::vector<uint8_t> partitionPicture(const Scene& scene, const Partition& partition,
                                      const PictureOptions& o) {
  FERRY_CHECK_EQ(partition.instanceOwners.size(), scene.instances.size());
  const int w = o.width, h = o.height;
  Canvas canvas(w, h, {236, 238, 242, 255});
  const CameraView& view = scene.view(o.view);
  const Camera camera(view, w, h);
  const std::unique_ptr<TraceBackend> geometry = makeEmbreeBackend(scene);
  std::vector<float> depth(size_t(w) * h, kInfinity);

  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, h, 16, 0, w, 64), [&](const tbb::blocked_range2d<int>& r) {
        for (int y = r.rows().begin(); y != r.rows().end(); ++y)
          for (int x = r.cols().begin(); x != r.cols().end(); ++x) {
            TraceRay ray{camera.origin(), camera.direction(x + 0.5f, y + 0.5f), 0, kInfinity};
            TraceHit hit = geometry->intersect(ray);
            if (!hit.valid()) continue;
            depth[size_t(y) * w + x] = hit.t;
            const Instance& inst = scene.instances[hit.instance];
            const Mesh& mesh = scene.meshes[scene.objects[inst.object].meshes[hit.slot]];
            const Vec3i& tri = mesh.indices[hit.primitive];
            Vec3f p0 = inst.transform.transformPoint(mesh.positions[tri.x]);
            Vec3f p1 = inst.transform.transformPoint(mesh.positions[tri.y]);
            Vec3f p2 = inst.transform.transformPoint(mesh.positions[tri.z]);
            Vec3f n = cross(p1 - p0, p2 - p0);
            float shade = 0.35f;
            if (length(n) > 0) shade += 0.65f * std::abs(dot(normalize(n), ray.direction));
            const RankSet& owners = partition.instanceOwners[hit.instance];
            const int count = owners.count();
            const int k = count > 1 ? ((x / kCheckerPixels) + (y / kCheckerPixels)) % count : 0;
            Rgba c = count > 0 ? scaled(rankColor(owners.nth(k)), shade) : Rgba{0, 0, 0, 255};
            canvas.blend(x, y, c);  // each pixel written by one thread only
          }
      });

  if (o.proxies) {
    for (const Proxy& p : partition.proxies) {
      const int count = p.owners.count();
      if (count == 0 || p.bounds.empty()) continue;
      const Box3f& b = p.bounds;
      auto corner = [&](int i) {
        return Vec3f((i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y,
                     (i & 4) ? b.upper.z : b.lower.z);
      };
      for (int i = 0; i < 8; ++i)
        for (int axis = 0; axis < 3; ++axis) {
          if (i & (1 << axis)) continue;
          const Vec3f a = corner(i), e = corner(i | (1 << axis));
          // Sample the edge in 3D so depth and perspective come out right.
          float ax, ay, ex, ey;
          int steps = 600;
          if (camera.project(a - camera.origin(), ax, ay) &&
              camera.project(e - camera.origin(), ex, ey))
            steps = std::clamp(int(2 * std::hypot(ex - ax, ey - ay)), 2, 8000);
          for (int s = 0; s <= steps; ++s) {
            const Vec3f q = lerp(a, e, float(s) / float(steps));
            const Vec3f d = q - camera.origin();
            float px, py;
            if (!camera.project(d, px, py)) continue;
            // Off the picture (or far off: no int holds it) before converting.
            if (!(px >= 0 && py >= 0 && px < float(w) && py < float(h))) continue;
            const int ix = int(std::floor(px)), iy = int(std::floor(py));
            const bool hidden = length(d) > depth[size_t(iy) * w + ix] * 1.0001f;
            const Rgba c = rankColor(p.owners.nth(count > 1 ? (s / 8) % count : 0));
            canvas.blend(ix, iy, c, hidden ? 0.12f : 0.55f);
          }
        }
    }
  }

  if (!o.title.empty()) {
    canvas.fillRect(0, 0, w, 22, {255, 255, 255, 255}, 0.8f);
    canvas.text(6, 5, o.title, {20, 20, 20, 255}, 1);
    int x = 6 + Canvas::textWidth(o.title) + 16;
    for (int r = 0; r < partition.ranks && x < w - 40; ++r) {
      canvas.fillRect(x, 6, x + 10, 16, rankColor(r));
      std::string label = std::to_string(r);
      canvas.text(x + 13, 5, label, {20, 20, 20, 255}, 1);
      x += 13 + Canvas::textWidth(label) + 8;
    }
  }
  return canvas.rgba();
}

}  // namespace ferry
