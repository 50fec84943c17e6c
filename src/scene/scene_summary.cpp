#include "scene/scene_summary.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "core/error.h"
#include "scene/scene.h"

namespace ferry {

SceneSummary summarize(const Scene& scene) {
  SceneSummary s;
  s.name = scene.name;
  s.uniqueMeshes = scene.meshes.size();
  for (const Mesh& m : scene.meshes) {
    s.triangles += m.triangleCount();
    s.vertices += m.vertexCount();
    s.memory += meshCost(m);
    if (scene.materials[m.material].isEmissive()) {
      ++s.emissiveMeshes;
      s.emissiveTriangles += m.triangleCount();
    }
  }
  s.geometries = scene.geometries.size();
  for (const Geometry& g : scene.geometries) {
    if (g.shape) {
      s.shapePrimitives += g.shape->primitiveCount();
      SceneSummary::ShapeKindCount& kind = s.shapeKinds[std::string(g.shape->kind())];
      ++kind.geometries;
      kind.primitives += g.shape->primitiveCount();
    }
    if (g.shape && g.shape->isVolume()) ++s.volumeBricks;
    s.memory += geometryCost(g);
  }
  s.objects = scene.objects.size();
  s.instances = scene.instances.size();
  for (const Instance& inst : scene.instances) s.movingInstances += inst.motion != nullptr;
  std::vector<uint64_t> trianglesPerObject(scene.objects.size(), 0);
  for (size_t o = 0; o < scene.objects.size(); ++o)
    for (int32_t m : scene.objects[o].meshes)
      trianglesPerObject[o] += scene.meshes[m].triangleCount();
  for (const Instance& inst : scene.instances)
    s.instancedTriangles += trianglesPerObject[inst.object];
  s.memory += instanceCost(scene.instances.size());
  s.textures = scene.textures.size();
  for (const Texture& t : scene.textures) {
    s.texels += t.texelCount();
    s.memory += textureCost(t);
  }
  for (const auto& table : scene.bsdfTables) s.memory += bsdfTableCost(*table);
  s.memory += mediaCost(scene);
  s.suns = scene.suns.size();
  s.pointLights = scene.pointLights.size();
  s.environments = scene.environment.isBlack() ? 0 : 1;
  s.views = scene.views.size();
  for (const ferry::Medium& m : scene.media) {
    SceneSummary::Medium out;
    out.name = m.name;
    if (m.cloud)
      out.kind = "cloud (procedural)";
    else if (m.homogeneous())
      out.kind = "homogeneous";
    else
      out.kind =
          fmt::format("{}grid {}x{}x{}{}", m.rgb ? "rgb " : "", m.density->nx(), m.density->ny(),
                      m.density->nz(), m.transfer ? " through a transfer function" : "");
    if (m.temperature)
      out.kind += ", emitting by temperature";
    else if (m.emits())
      out.kind += ", emitting";
    out.bytes = m.bytes();
    if (m.density) {
      out.minDensity = m.density->minValue();
      out.maxDensity = m.density->maxValue();
    } else if (m.cloud) {
      out.minDensity = 0;  // pbrt-v4's cloud density lies in [0, 1]
      out.maxDensity = 1;
    }
    out.sigmaA = m.sigmaA;
    out.sigmaS = m.sigmaS;
    out.g = m.g;
    s.media.push_back(out);
  }
  s.mediumBoundaries = scene.mediumBoundaries.size();
  for (const MediumBoundary& b : scene.mediumBoundaries)
    s.boundaryTriangles += b.mesh.triangleCount();
  s.bounds = scene.worldBounds();
  return s;
}

MemoryCost ownedMemory(const Scene& scene, const std::vector<int32_t>& instances) {
  std::vector<uint8_t> object(scene.objects.size(), 0), mesh(scene.meshes.size(), 0),
      geometry(scene.geometries.size(), 0), texture(scene.textures.size(), 0),
      table(scene.bsdfTables.size(), 0);
  for (int32_t i : instances) object[scene.instances[i].object] = 1;
  // Every rank holds the media whole.
  MemoryCost cost = instanceCost(instances.size());
  cost += mediaCost(scene);
  for (size_t o = 0; o < object.size(); ++o)
    if (object[o]) {
      for (int32_t m : scene.objects[o].meshes) mesh[m] = 1;
      for (int32_t g : scene.objects[o].geometries) geometry[g] = 1;
    }
  for (size_t m = 0; m < mesh.size(); ++m) {
    if (!mesh[m]) continue;
    cost += meshCost(scene.meshes[m]);
    scene.forEachShadingTexture(scene.meshes[m].material,
                                [&](int32_t t) { texture[size_t(t)] = 1; });
    scene.forEachShadingBsdfTable(scene.meshes[m].material,
                                  [&](int32_t t) { table[size_t(t)] = 1; });
  }
  for (size_t g = 0; g < geometry.size(); ++g) {
    if (!geometry[g]) continue;
    cost += geometryCost(scene.geometries[g]);
    scene.forEachShadingTexture(scene.geometries[g].material,
                                [&](int32_t t) { texture[size_t(t)] = 1; });
    scene.forEachShadingBsdfTable(scene.geometries[g].material,
                                  [&](int32_t t) { table[size_t(t)] = 1; });
  }
  for (size_t t = 0; t < texture.size(); ++t)
    if (texture[t]) cost += textureCost(scene.textures[t]);
  for (size_t t = 0; t < table.size(); ++t)
    if (table[t]) cost += bsdfTableCost(*scene.bsdfTables[t]);
  return cost;
}

std::string formatCount(uint64_t n) {
  if (n < 10000) return fmt::format("{}", n);
  const char* units[] = {"K", "M", "G", "T", "P"};
  double v = double(n);
  int u = -1;
  while (v >= 1000 && u < 4) {
    v /= 1000;
    ++u;
  }
  return fmt::format("{:.3g} {}", v, units[u]);
}

std::string formatBytes(uint64_t bytes) {
  if (bytes < 1024) return fmt::format("{} B", bytes);
  const char* units[] = {"KiB", "MiB", "GiB", "TiB", "PiB"};
  double v = double(bytes);
  int u = -1;
  while (v >= 1024 && u < 4) {
    v /= 1024;
    ++u;
  }
  return fmt::format("{:.2f} {}", v, units[u]);
}

uint64_t parseBytes(const std::string& text, const std::string& what) {
  auto bad = [&] {
    return InputError(fmt::format(
        "{} '{}': expected a size such as 2GiB, 500MiB, 3GB or a number of bytes", what, text));
  };
  size_t end = 0;
  double value = 0;
  try {
    value = std::stod(text, &end);
  } catch (const std::exception&) {
    throw bad();
  }
  std::string unit = text.substr(end);
  unit.erase(0, unit.find_first_not_of(' '));
  static const std::pair<const char*, double> units[] = {
      {"", 1},       {"B", 1},        {"K", 0x1p10},   {"KiB", 0x1p10}, {"KB", 1e3},
      {"M", 0x1p20}, {"MiB", 0x1p20}, {"MB", 1e6},     {"G", 0x1p30},   {"GiB", 0x1p30},
      {"GB", 1e9},   {"T", 0x1p40},   {"TiB", 0x1p40}, {"TB", 1e12}};
  for (const auto& [name, scale] : units)
    if (unit == name) {
      const double bytes = value * scale;
      if (!(bytes >= 1 && bytes < 0x1p63)) throw bad();
      return uint64_t(bytes);
    }
  throw bad();
}

nlohmann::json SceneSummary::toJson() const {
  nlohmann::json j;
  j["name"] = name;
  j["unique_meshes"] = uniqueMeshes;
  j["geometries"] = geometries;
  j["shape_primitives"] = shapePrimitives;
  for (const auto& [kind, count] : shapeKinds)
    j["shape_kinds"][kind] = {{"geometries", count.geometries}, {"primitives", count.primitives}};
  j["volume_bricks"] = volumeBricks;
  j["triangles"] = triangles;
  j["vertices"] = vertices;
  j["objects"] = objects;
  j["instances"] = instances;
  if (movingInstances) j["moving_instances"] = movingInstances;
  j["instanced_triangles"] = instancedTriangles;
  j["textures"] = textures;
  j["texels"] = texels;
  j["lights"] = {{"total", lights()},
                 {"suns", suns},
                 {"environments", environments},
                 {"emissive_meshes", emissiveMeshes},
                 {"emissive_triangles", emissiveTriangles}};
  // (Only when there are any: older summaries, in checkpoints, have none.)
  if (pointLights > 0) j["lights"]["point_lights"] = pointLights;
  j["views"] = views;
  // (Only when there are media: the summary is part of a checkpoint's scene
  // identity, which scenes without media keep as it was.)
  if (!media.empty() || mediumBoundaries > 0) {
    nlohmann::json list = nlohmann::json::array();
    for (const Medium& m : media)
      list.push_back({{"name", m.name},
                      {"kind", m.kind},
                      {"bytes", m.bytes},
                      {"density", {m.minDensity, m.maxDensity}},
                      {"sigma_a", {m.sigmaA.x, m.sigmaA.y, m.sigmaA.z}},
                      {"sigma_s", {m.sigmaS.x, m.sigmaS.y, m.sigmaS.z}},
                      {"g", m.g}});
    j["media"] = {{"media", list},
                  {"boundaries", mediumBoundaries},
                  {"boundary_triangles", boundaryTriangles}};
  }
  if (!bounds.empty())
    j["bounds"] = {{bounds.lower.x, bounds.lower.y, bounds.lower.z},
                   {bounds.upper.x, bounds.upper.y, bounds.upper.z}};
  j["memory_bytes"] = {{"total", memory.total()},       {"vertices", memory.vertices},
                       {"normals", memory.normals},     {"uvs", memory.uvs},
                       {"indices", memory.indices},     {"texels", memory.texels},
                       {"instances", memory.instances}, {"accel", memory.accel},
                       {"shapes", memory.shapes}};
  // (Only with media: older summaries, in checkpoints, have no such field.)
  if (memory.media > 0) j["memory_bytes"]["media"] = memory.media;
  return j;
}

std::string SceneSummary::toText() const {
  std::string out;
  auto row = [&](const std::string& label, const std::string& value) {
    out += fmt::format("  {:<21} {}\n", label, value);  // a long label keeps a space
  };
  out += fmt::format("scene {}\n", name);
  row("unique meshes", formatCount(uniqueMeshes));
  if (geometries > 0)
    row("other geometries",
        fmt::format("{} ({} primitives)", formatCount(geometries), formatCount(shapePrimitives)));
  for (const auto& [kind, count] : shapeKinds)
    row("  " + kind, fmt::format("{} ({} primitives)", formatCount(count.geometries),
                                 formatCount(count.primitives)));
  row("triangles", formatCount(triangles));
  row("vertices", formatCount(vertices));
  row("objects", formatCount(objects));
  row("instances", movingInstances ? fmt::format("{} ({} moving)", formatCount(instances),
                                                 formatCount(movingInstances))
                                   : formatCount(instances));
  row("instanced triangles", formatCount(instancedTriangles));
  row("textures", fmt::format("{} ({} texels)", textures, formatCount(texels)));
  row("lights", fmt::format("{} ({} sun, {} point or spot, {} environment, {} emissive meshes / {} "
                            "triangles)",
                            lights(), suns, pointLights, environments, emissiveMeshes,
                            formatCount(emissiveTriangles)));
  row("views", fmt::format("{}", views));
  if (!media.empty() || mediumBoundaries > 0) {
    row("media", fmt::format("{} ({} boundary meshes / {} triangles)", media.size(),
                             mediumBoundaries, formatCount(boundaryTriangles)));
    for (const Medium& m : media)
      row("  " + m.name,
          fmt::format("{}, density {:.4g} .. {:.4g}, {}, sigma_a ({:.4g}, {:.4g}, {:.4g}), "
                      "sigma_s ({:.4g}, {:.4g}, {:.4g}), g {:.3g}",
                      m.kind, m.minDensity, m.maxDensity, formatBytes(m.bytes), m.sigmaA.x,
                      m.sigmaA.y, m.sigmaA.z, m.sigmaS.x, m.sigmaS.y, m.sigmaS.z, m.g));
  }
  if (!bounds.empty())
    row("bounds", fmt::format("({:.4g}, {:.4g}, {:.4g}) - ({:.4g}, {:.4g}, {:.4g})", bounds.lower.x,
                              bounds.lower.y, bounds.lower.z, bounds.upper.x, bounds.upper.y,
                              bounds.upper.z));
  out += "  estimated memory\n";
  row("  total", formatBytes(memory.total()));
  row("  vertices", formatBytes(memory.vertices));
  row("  normals", formatBytes(memory.normals));
  row("  uvs", formatBytes(memory.uvs));
  row("  indices", formatBytes(memory.indices));
  row("  texels", formatBytes(memory.texels));
  if (memory.shapes > 0) row("  shapes", formatBytes(memory.shapes));
  if (memory.media > 0) row("  media (every rank)", formatBytes(memory.media));
  row("  instances", formatBytes(memory.instances));
  row("  acceleration", formatBytes(memory.accel));
  return out;
}

}  // namespace ferry
