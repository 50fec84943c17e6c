// The real scenes in ../shared/scenes (made by others, not in the repository):
// each loads with the counts its SOURCE.txt gives, `ferry info` agrees, and a
// small render through `ferry render` looks roughly right (coarse image
// statistics; the pictures were also checked by eye). Skipped when the
// directory is absent.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "io/images/image_io.h"
#include "io/scene_loader.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = FERRY_SHARED_SCENES;

#define REQUIRE_SCENE(relative)                                \
  const std::string scenePath = (kScenes / relative).string(); \
  if (!fs::exists(scenePath)) GTEST_SKIP() << scenePath << " is not available"

struct CommandResult {
  int status = 0;
  std::string out, err;
};

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

CommandResult ferry(const std::string& args, const fs::path& cwd = fs::temp_directory_path()) {
  static int counter = 0;
  fs::path base = fs::temp_directory_path() /
                  ("ferry_real_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::string cmd = "cd " + shellQuote(cwd.string()) + " && " + shellQuote(FERRY_BINARY) + " " +
                    args + " > " + shellQuote(base.string() + ".out") + " 2> " +
                    shellQuote(base.string() + ".err");
  CommandResult r;
  r.status = std::system(cmd.c_str());
  auto slurp = [](const std::string& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  r.out = slurp(base.string() + ".out");
  r.err = slurp(base.string() + ".err");
  fs::remove(base.string() + ".out");
  fs::remove(base.string() + ".err");
  return r;
}

// `ferry info --json` against the loader's own summary.
void expectInfoAgrees(const std::string& scene, const SceneSummary& s,
                      const std::string& flags = "") {
  CommandResult r = ferry("info --json " + flags + " " + shellQuote(scene));
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.dump(), s.toJson().dump());
}

struct Image {
  LinearImage image;
  Vec3f mean(int x0, int y0, int x1, int y1) const {
    Vec3f sum(0);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) sum += image.rgb[size_t(y) * image.width + x];
    return sum / float((x1 - x0) * (y1 - y0));
  }
};

Image render(const std::string& scene, const std::string& flags) {
  fs::path out = fs::temp_directory_path() / ("ferry_real_" + std::to_string(::getpid()) + ".pfm");
  CommandResult r = ferry("render " + shellQuote(scene) + " -q --spp 4 -o " +
                          shellQuote(out.string()) + " " + flags);
  EXPECT_EQ(r.status, 0) << r.err;
  Image img;
  img.image = readPfm(out.string());
  fs::remove(out);
  return img;
}

TEST(RealScenes, StanfordBunny) {
  REQUIRE_SCENE("stanford-bunny/bun_zipper.ply");
  Scene scene = loadScene(scenePath);
  SceneSummary s = summarize(scene);
  EXPECT_EQ(s.triangles, 69451u);
  EXPECT_EQ(s.vertices, 35947u);
  EXPECT_EQ(s.instances, 1u);
  expectInfoAgrees(scenePath, s);
  for (const char* smaller :
       {"bun_zipper_res2.ply", "bun_zipper_res3.ply", "bun_zipper_res4.ply"}) {
    Scene low = loadScene((kScenes / "stanford-bunny" / smaller).string());
    EXPECT_LT(low.meshes[0].triangleCount(), s.triangles);
  }
  Image img = render(scenePath, "--size 64x48");
  // The sky (0.5) around a lit white bunny in the middle.
  Vec3f corner = img.mean(0, 0, 6, 6), middle = img.mean(26, 18, 38, 30);
  EXPECT_NEAR(luminance(corner), 0.5f, 0.05f);
  EXPECT_GT(luminance(middle), 0.6f);
}

TEST(RealScenes, BuddhaFractal) {
  REQUIRE_SCENE("buddha-fractal/buddha-fractal.pbrt");
  Scene scene = loadScene(scenePath);
  SceneSummary s = summarize(scene);
  // One 29,890-triangle mesh instanced 25,250 times, plus the ground quad.
  EXPECT_EQ(s.uniqueMeshes, 2u);
  EXPECT_EQ(s.triangles, 29890u + 2u);
  EXPECT_EQ(s.vertices, 89670u + 6u);
  EXPECT_EQ(s.instances, 25251u);
  EXPECT_EQ(s.instancedTriangles, 29890ull * 25250ull + 2ull);
  EXPECT_EQ(scene.filmWidth, 750);
  EXPECT_EQ(scene.filmHeight, 1200);
  expectInfoAgrees(scenePath, s);
  Image img = render(scenePath, "--size 40x64");
  // The sky is the infinite light's colour: (0.945, 0.984, 1) * 1.1.
  Vec3f sky = img.mean(0, 0, 4, 4);
  EXPECT_NEAR(sky.z, 1.1f, 0.05f);
  EXPECT_LT(sky.x, sky.z);
  // The ground in front is lit (its file normals lie in its plane: dropped).
  EXPECT_GT(luminance(img.mean(0, 58, 8, 64)), 0.2f);
  // The statue of statues stands in the middle.
  EXPECT_LT(luminance(img.mean(16, 24, 24, 40)), luminance(sky));
}

// pbrt-v3's bathroom against pbrt-v3's own render (../shared/references):
// the guard of the fidelity goals at a size the suite affords (150x95, 16 spp,
// a fixed seed: one image, so the figures cannot wander). Each region tests
// one pbrt-v3 semantic: the whole image its mirrored lights (+150..220 %
// when seen and sampled on one side), the upper half its walls' sided
// paint.bsdf (0.4 to 0.6 of the reference on the table's top), the mats
// their solid fbm bump (1.14 to 1.19 without it). bench/fidelity measures
// the same at 300x190 and 256 spp (docs/fidelity.md).
TEST(RealScenes, BathroomMatchesPbrtV3sRender) {
  REQUIRE_SCENE("bathroom/bathroom.pbrt");
  const fs::path reference = kScenes.parent_path() / "references" / "bathroom.exr";
  if (!fs::exists(reference)) GTEST_SKIP() << reference << " is not available";
  const fs::path out =
      fs::temp_directory_path() / ("ferry_bathroom_" + std::to_string(::getpid()) + ".pfm");
  const CommandResult r =
      ferry("render " + shellQuote(scenePath) + " -q --size 150x95 --spp 16 --seed 1 -o " +
            shellQuote(out.string()));
  ASSERT_EQ(r.status, 0) << r.err;
  const LinearImage ferryImage = readPfm(out.string());
  fs::remove(out);
  const HdrImage pbrt = readHdrImage(reference.string());
  // The mean of a region (fractions of the image, y down) of either image.
  auto mean = [](int width, int height, auto pixel, float x0, float x1, float y0, float y1) {
    Vec3f sum(0);
    int n = 0;
    for (int y = int(y0 * float(height)); y < int(y1 * float(height)); ++y)
      for (int x = int(x0 * float(width)); x < int(x1 * float(width)); ++x, ++n) sum += pixel(x, y);
    return sum / float(n);
  };
  struct Region {
    const char* name;
    float x0, x1, y0, y1, tolerance;
  };
  for (const Region& g : {Region{"whole image", 0, 1, 0, 1, 0.05f},
                          Region{"upper half (walls)", 0, 1, 0, 0.5f, 0.08f},
                          Region{"bath mats", 0.52f, 0.74f, 0.6f, 1, 0.08f}}) {
    const Vec3f f = mean(
        ferryImage.width, ferryImage.height,
        [&](int x, int y) {
          return ferryImage.rgb[size_t(y) * size_t(ferryImage.width) + size_t(x)];
        },
        g.x0, g.x1, g.y0, g.y1);
    const Vec3f p = mean(
        pbrt.width, pbrt.height, [&](int x, int y) { return pbrt.at(x, y); }, g.x0, g.x1, g.y0,
        g.y1);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(f[k] / p[k], 1.0f, g.tolerance) << g.name << " ch" << k;
  }
}

TEST(RealScenes, BmwM6) {
  REQUIRE_SCENE("bmw-m6/bmw-m6.pbrt");
  // As given, its environment map is missing: a clear error naming it.
  try {
    loadScene(scenePath);
    FAIL() << "loaded without textures/sky.exr";
  } catch (const InputError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find("bmw-m6.pbrt:15:1: environment map \"textures/sky.exr\" not found"),
              std::string::npos)
        << m;
  }
  CommandResult failed =
      ferry("render " + shellQuote(scenePath) + " -q --size 8x8 -o /tmp/never.png");
  EXPECT_NE(failed.status, 0);
  EXPECT_NE(failed.err.find("textures/sky.exr"), std::string::npos) << failed.err;
  EXPECT_NE(failed.err.find("env-fallback"), std::string::npos) << failed.err;

  LoadOptions fallback;
  fallback.envFallback = true;
  fallback.warn = [](const std::string&) {};
  Scene scene = loadScene(scenePath, fallback);
  SceneSummary s = summarize(scene);
  EXPECT_EQ(s.uniqueMeshes, 114u);
  EXPECT_EQ(s.triangles, 792746u);
  EXPECT_EQ(s.vertices, 525850u);
  EXPECT_EQ(s.instances, 114u);
  EXPECT_EQ(scene.environment.color, Vec3f(1));
  EXPECT_TRUE(scene.views.at(0).leftHanded);
  expectInfoAgrees(scenePath, s, "--env-fallback");
  Image img = render(scenePath, "--size 56x40 --env-fallback");
  // The red car paint fills the middle of the picture, under the white sky
  // its coat reflects: red is 1.54x green there in pbrt-v3's own render
  // (280x200, 256 spp), 1.52x in Ferry's.
  Vec3f car = img.mean(16, 16, 40, 28);
  EXPECT_GT(car.x, 1.3f * car.y);
  EXPECT_GT(car.x, 1.3f * car.z);
}

TEST(RealScenes, DamagedHelmet) {
  REQUIRE_SCENE("damaged-helmet/glTF-Binary/DamagedHelmet.glb");
  LoadOptions quiet;
  quiet.warn = [](const std::string&) {};
  Scene glb = loadScene(scenePath, quiet);
  Scene gltf = loadScene((kScenes / "damaged-helmet/glTF/DamagedHelmet.gltf").string(), quiet);
  SceneSummary s = summarize(glb), t = summarize(gltf);
  EXPECT_EQ(s.triangles, 15452u);
  EXPECT_EQ(s.objects, 1u);
  EXPECT_EQ(s.instances, 1u);
  EXPECT_GT(s.emissiveTriangles, 0u);               // its emissive texture, baked per triangle
  EXPECT_EQ(s.toJson().dump(), t.toJson().dump());  // .glb and .gltf+.bin: the same scene
  expectInfoAgrees(scenePath, s);
  Image img = render(scenePath, "--size 48x48");
  EXPECT_NEAR(luminance(img.mean(0, 0, 4, 4)), 0.5f, 0.05f);  // sky around
  Vec3f middle = img.mean(18, 18, 30, 30);
  EXPECT_GT(std::abs(luminance(middle) - 0.5f), 0.05f);  // the helmet in front of it
}

TEST(RealScenes, FilmGivesSizeAndOutputWhenTheCommandLineDoesNot) {
  // The corpus's features_v3.pbrt asks for 200 x 100 pixels in features.exr,
  // cropped to [0.25, 0.75) x [0, 0.5): 100 x 50 of them.
  fs::path dir = fs::temp_directory_path() / ("ferry_film_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::path scene = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "pbrt" / "features_v3.pbrt";
  CommandResult r = ferry("render " + shellQuote(scene.string()) + " -q --spp 1", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  HdrImage out = readHdrImage((dir / "features.exr").string());
  EXPECT_EQ(out.width, 100);
  EXPECT_EQ(out.height, 50);
  // Given on the command line, --size, --crop and -o win (the film's crop
  // still applies to another size).
  r = ferry("render " + shellQuote(scene.string()) + " -q --spp 1 --size 20x10 -o small.pfm", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(readPfm((dir / "small.pfm").string()).width, 10);
  EXPECT_EQ(readPfm((dir / "small.pfm").string()).height, 5);
  r = ferry("render " + shellQuote(scene.string()) +
                " -q --spp 1 --size 20x10 --crop 0,1,0,1 -o whole.pfm",
            dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(readPfm((dir / "whole.pfm").string()).width, 20);
  fs::remove_all(dir);
}

// pbrt's Integrator "integer maxdepth" is the path depth when --max-depth is
// not given, also from a part directory (its manifest keeps it, and the
// Integrator's name, which turns light paths on for "bdpt").
TEST(RealScenes, IntegratorMaxDepthIsTheDefaultDepth) {
  fs::path dir = fs::temp_directory_path() / ("ferry_depth_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // Integrator "bdpt" "integer maxdepth" 7, and an area light for light
  // paths to leave (they start at emissive shapes, not at point lights).
  fs::path scene = dir / "bdpt.pbrt";
  std::ofstream(scene) << "Integrator \"bdpt\" \"integer maxdepth\" 7\nCamera \"perspective\"\n"
                          "Film \"rgb\"\nWorldBegin\nShape \"sphere\" \"float radius\" 0.5\n"
                          "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                          "Translate 0 3 5\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n";
  auto maxDepth = [&](const std::string& stats) {
    std::ifstream in(dir / stats);
    return nlohmann::json::parse(in).at("settings").at("max_depth").get<int>();
  };
  auto lightPaths = [&](const std::string& stats) {
    std::ifstream in(dir / stats);
    return nlohmann::json::parse(in).at("render").at("frames").at(0).at("light_paths").get<int>();
  };
  const std::string common = " -q --spp 1 --size 8x16 -o out.pfm --stats ";
  CommandResult r = ferry("render " + shellQuote(scene.string()) + common + "scene.json", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(maxDepth("scene.json"), 7);
  EXPECT_GT(lightPaths("scene.json"), 0);
  r = ferry("render " + shellQuote(scene.string()) + common + "flag.json --max-depth 2", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(maxDepth("flag.json"), 2);
  r = ferry("partition " + shellQuote(scene.string()) + " -q --ranks 1 -o parts", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  r = ferry("render parts" + common + "parts.json", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(maxDepth("parts.json"), 7);
  EXPECT_GT(lightPaths("parts.json"), 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ferry
