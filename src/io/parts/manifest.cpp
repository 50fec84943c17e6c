#include "io/parts/manifest.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <type_traits>

#include "core/error.h"
#include "core/hash64.h"
#include "io/images/image_io.h"
#include "io/json_numbers.h"
#include "io/parts/part_file.h"
#include "io/text_file.h"
#include "scene/scene.h"

namespace ferry {
namespace {

std::string manifestPath(const std::string& directory) {
  return (std::filesystem::path(directory) / kManifestName).string();
}

nlohmann::json fileJson(const ManifestFile& f) {
  return {{"file", f.file}, {"bytes", f.bytes}, {"hash", hashToHex(f.hash)}};
}

uint64_t parseHash(const std::string& hex, const std::string& where) {
  if (hex.size() != 16 || hex.find_first_not_of("0123456789abcdef") != std::string::npos)
    throw InputError(fmt::format("{}: bad hash '{}'", where, hex));
  return std::stoull(hex, nullptr, 16);
}

void readFile(const nlohmann::json& j, ManifestFile& f, const std::string& where) {
  f.file = j.at("file").get<std::string>();
  f.bytes = checkedNumber<uint64_t>(j, "bytes");
  f.hash = parseHash(j.at("hash").get<std::string>(), where);
  // Files live in the directory: no absolute paths, no way out of it.
  std::filesystem::path p(f.file);
  if (f.file.empty() || p.is_absolute() || p.has_parent_path())
    throw InputError(fmt::format("{}: bad file name '{}'", where, f.file));
}

}  // namespace

nlohmann::json Manifest::toJson() const {
  nlohmann::json j;
  j["format"] = kManifestFormat;
  j["version"] = version;
  j["scene"] = scene;
  j["partitioner"] = partitioner;
  j["options"] = options;
  j["ranks"] = ranks;
  j["summary"] = summary;
  j["film_scale"] = filmScale;
  if (filmMaxSampleLuminance > 0) j["film_max_sample_luminance"] = filmMaxSampleLuminance;
  if (filmMaxComponentValue > 0) j["film_max_component_value"] = filmMaxComponentValue;
  if (filmCrop) j["film_crop"] = *filmCrop;
  if (!integrator.empty()) j["integrator"] = integrator;
  if (integratorMaxDepth) j["integrator_max_depth"] = *integratorMaxDepth;
  j["shutter"] = {shutterOpen, shutterClose};
  j["motion_times"] = {motionStart, motionEnd};
  j["input_bytes"] = inputBytes;
  j["replicated_bytes"] = replicatedBytes;
  j["proxies"] = proxies;
  j["partition_seconds"] = partitionSeconds;
  j["shared"] = fileJson(shared);
  nlohmann::json parts = nlohmann::json::array();
  for (const ManifestPart& p : this->parts) {
    nlohmann::json e = fileJson(p);
    e["rank"] = p.rank;
    e["instances"] = p.instances;
    e["estimated_bytes"] = p.estimatedBytes;
    parts.push_back(e);
  }
  j["parts"] = parts;
  if (!predictions.empty()) j["predictions"] = predictions;
  return j;
}

bool isPartDirectory(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec) && std::filesystem::exists(manifestPath(path), ec);
}

void writeManifest(const std::string& directory, const Manifest& manifest) {
  const std::string path = manifestPath(directory);
  writeFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp);
    out << manifest.toJson().dump(2) << "\n";
    out.close();
    if (!out) throw InputError(fmt::format("{}: could not write", path));
  });
}

Manifest readManifest(const std::string& directory) {
  const std::string path = manifestPath(directory);
  const std::string text = readTextFile(path, "the part directory's manifest");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: not valid JSON ({})", path, e.what()));
  }
  Manifest m;
  try {
    if (!j.is_object() || j.value("format", std::string()) != kManifestFormat)
      throw InputError(fmt::format("{}: not a Ferry part manifest", path));
    m.version = checkedNumber<uint32_t>(j, "version");
    if (m.version < kOldestPartFormatVersion || m.version > kPartFormatVersion)
      throw InputError(fmt::format(
          "{}: made by another version of Ferry (part format {}, this Ferry reads formats "
          "{} to {}): partition the scene again",
          path, m.version, kOldestPartFormatVersion, kPartFormatVersion));
    m.scene = j.at("scene").get<std::string>();
    m.partitioner = j.at("partitioner").get<std::string>();
    m.options = j.value("options", nlohmann::json::object());
    m.ranks = checkedNumber<int>(j, "ranks");
    m.summary = j.at("summary");
    summaryFromJson(m.summary);  // its numbers checked here, where an error names the file
    m.filmScale =
        checkedNumberOr(j, "film_scale", 1.0f);  // absent in directories made before it existed
    if (!(m.filmScale > 0) || !std::isfinite(m.filmScale))
      throw InputError(fmt::format("{}: bad film_scale {}", path, m.filmScale));
    m.filmMaxSampleLuminance = checkedNumberOr(j, "film_max_sample_luminance", 0.0f);
    m.filmMaxComponentValue = checkedNumberOr(j, "film_max_component_value", 0.0f);
    if (!(m.filmMaxSampleLuminance >= 0) || !std::isfinite(m.filmMaxSampleLuminance) ||
        !(m.filmMaxComponentValue >= 0) || !std::isfinite(m.filmMaxComponentValue))
      throw InputError(
          fmt::format("{}: bad film_max_sample_luminance or film_max_component_value", path));
    if (j.contains("film_crop")) {
      const nlohmann::json& cropJson = j.at("film_crop");
      std::vector<float> crop;
      if (cropJson.is_array())
        for (const nlohmann::json& v : cropJson) crop.push_back(checkedNumber<float>(v));
      if (crop.size() != 4 || !isCropWindow(crop[0], crop[1], crop[2], crop[3]))
        throw InputError(fmt::format("{}: bad film_crop", path));
      m.filmCrop = std::array<float, 4>{crop[0], crop[1], crop[2], crop[3]};
    }
    m.integrator = j.value("integrator", std::string());
    if (j.contains("integrator_max_depth")) {
      m.integratorMaxDepth = checkedNumber<int>(j, "integrator_max_depth");
      if (*m.integratorMaxDepth < 0)
        throw InputError(
            fmt::format("{}: bad integrator_max_depth {}", path, *m.integratorMaxDepth));
    }
    auto pair = [&](const char* key, float& a, float& b) {  // absent in older directories
      if (!j.contains(key)) return;
      const nlohmann::json& v = j.at(key);
      if (!v.is_array() || v.size() != 2)
        throw InputError(fmt::format("{}: bad {} (expected two numbers)", path, key));
      a = checkedNumber<float>(v[0]), b = checkedNumber<float>(v[1]);
      if (!std::isfinite(a) || !std::isfinite(b) || a > b)
        throw InputError(fmt::format("{}: bad {} ({} to {})", path, key, a, b));
    };
    pair("shutter", m.shutterOpen, m.shutterClose);
    pair("motion_times", m.motionStart, m.motionEnd);
    m.inputBytes = checkedNumberOr(j, "input_bytes", uint64_t(0));
    m.replicatedBytes = checkedNumberOr(j, "replicated_bytes", uint64_t(0));
    m.proxies = checkedNumberOr(j, "proxies", uint64_t(0));
    m.partitionSeconds = checkedNumberOr(j, "partition_seconds", 0.0);
    m.predictions = j.value("predictions", nlohmann::json::array());
    if (!m.predictions.is_array())
      throw InputError(fmt::format("{}: predictions must be an array", path));
    readFile(j.at("shared"), m.shared, path);
    const nlohmann::json& parts = j.at("parts");
    if (m.ranks < 1 || m.ranks > (m.version == 1 ? 64 : kMaxRanks) || !parts.is_array() ||
        parts.size() != size_t(m.ranks))
      throw InputError(
          fmt::format("{}: {} parts listed for {} ranks", path, parts.size(), m.ranks));
    for (size_t r = 0; r < parts.size(); ++r) {
      ManifestPart p;
      readFile(parts[r], p, path);
      p.rank = checkedNumber<int>(parts[r], "rank");
      if (p.rank != int(r))
        throw InputError(fmt::format("{}: part {} is listed as rank {}", path, r, p.rank));
      p.instances = checkedNumberOr(parts[r], "instances", uint64_t(0));
      p.estimatedBytes = checkedNumberOr(parts[r], "estimated_bytes", uint64_t(0));
      m.parts.push_back(std::move(p));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: missing or bad field ({})", path, e.what()));
  }
  return m;
}

SceneSummary summaryFromJson(const nlohmann::json& j) {
  SceneSummary s;
  auto count = [](const nlohmann::json& o, const char* key) {
    return checkedNumberOr(o, key, uint64_t(0));
  };
  s.name = j.value("name", std::string());
  s.uniqueMeshes = count(j, "unique_meshes");
  s.triangles = count(j, "triangles");
  s.geometries = count(j, "geometries");
  s.shapePrimitives = count(j, "shape_primitives");
  s.volumeBricks = count(j, "volume_bricks");
  s.vertices = count(j, "vertices");
  s.objects = count(j, "objects");
  s.instances = count(j, "instances");
  s.movingInstances = count(j, "moving_instances");
  s.instancedTriangles = count(j, "instanced_triangles");
  s.textures = count(j, "textures");
  s.texels = count(j, "texels");
  s.views = count(j, "views");
  if (j.contains("lights")) {
    const auto& l = j["lights"];
    s.suns = count(l, "suns");
    if (l.contains("point_lights")) s.pointLights = count(l, "point_lights");
    s.environments = count(l, "environments");
    s.emissiveMeshes = count(l, "emissive_meshes");
    s.emissiveTriangles = count(l, "emissive_triangles");
  }
  if (j.contains("bounds") && j["bounds"].is_array() && j["bounds"].size() == 2) {
    const auto& b = j["bounds"];
    s.bounds.lower = {checkedNumber<float>(b.at(0).at(0)), checkedNumber<float>(b.at(0).at(1)),
                      checkedNumber<float>(b.at(0).at(2))};
    s.bounds.upper = {checkedNumber<float>(b.at(1).at(0)), checkedNumber<float>(b.at(1).at(1)),
                      checkedNumber<float>(b.at(1).at(2))};
  }
  if (j.contains("memory_bytes")) {
    const auto& m = j["memory_bytes"];
    s.memory.vertices = count(m, "vertices");
    s.memory.normals = count(m, "normals");
    s.memory.uvs = count(m, "uvs");
    s.memory.indices = count(m, "indices");
    s.memory.texels = count(m, "texels");
    s.memory.instances = count(m, "instances");
    s.memory.accel = count(m, "accel");
    if (m.contains("media")) s.memory.media = count(m, "media");
    if (m.contains("shapes")) s.memory.shapes = count(m, "shapes");
  }
  return s;
}

}  // namespace ferry
