// The library's Session: a named scene renders what the command's session
// renders, bit for bit; the same scene handed over from memory (borrowed
// arrays) renders the same image; in-process ranks give the 1-rank image;
// errors are api::Error on every rank, with the failing rank's message.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>

#include "api/session_on.h"
#include "comm/in_process_communicator.h"
#include "ferry/ferry.h"
#include "io/scene_loader.h"
#include "session/render_session.h"

namespace ferry {
namespace {

// The message of the api::Error f throws, or "no error".
template <class F>
std::string message(F&& f) {
  try {
    f();
  } catch (const api::Error& e) {
    return std::string(e.what());
  }
  return std::string("no error");
}

api::Options smallOptions() {
  api::Options o;
  o.width = 48;
  o.height = 36;
  o.samplesPerPixel = 2;
  o.seed = 3;
  o.threads = 1;
  return o;
}

// What the command's code path (RenderSession over an image sink) renders.
struct LinearSink final : FrameSink {
  Frames frames() const override { return Frames::Last; }
  Pixels pixels() const override { return Pixels::Linear; }
  void receive(const FrameImage& image) override {
    if (image.last) linear = image.linear;
  }
  std::vector<Vec3f> linear;
};

std::vector<Vec3f> commandImage(const std::string& scene, const api::Options& o, int frames) {
  SessionSettings s;
  s.scene = scene;
  s.render.width = o.width;
  s.render.height = o.height;
  s.render.samplesPerPixel = o.samplesPerPixel;
  s.render.frames = frames;
  s.render.seed = o.seed;
  s.threads = o.threads;
  InProcessGroup alone(1);
  RenderSession session(s, alone.communicator(0));
  LinearSink sink;
  session.run(sink);
  return sink.linear;
}

std::vector<Vec3f> rgbOf(const api::Image& image) {
  std::vector<Vec3f> out(size_t(image.width) * image.height);
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = Vec3f(image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2]);
  return out;
}

TEST(ApiSession, ANamedSceneRendersTheCommandsImage) {
  const api::Options o = smallOptions();
  const api::Image image = api::render("builtin:cornell", o, 2);
  ASSERT_EQ(image.width, 48);
  ASSERT_EQ(image.height, 36);
  ASSERT_EQ(image.rgba.size(), size_t(48 * 36 * 4));
  EXPECT_EQ(rgbOf(image), commandImage("builtin:cornell", o, 2));
  for (size_t i = 3; i < image.rgba.size(); i += 4) ASSERT_EQ(image.rgba[i], 1.0f);
}

// The cornell box handed over as arrays (borrowed, as a simulation would):
// its meshes, materials, instances, lights and camera.
api::Image cornellFromMemory(api::Session& session, const Scene& cornell) {
  std::vector<int> materials;
  for (size_t m = 1; m < cornell.materials.size() + 1; ++m) {
    const Material& material = cornell.materials[m - 1];
    EXPECT_EQ(material.model->name(), "diffuse");
    api::MaterialData data;
    data.name = material.name;
    data.color = {material.baseColor.x, material.baseColor.y, material.baseColor.z};
    data.emission = {material.emission.x, material.emission.y, material.emission.z};
    materials.push_back(session.addMaterial(data));
  }
  std::vector<int> meshes;
  for (const Mesh& mesh : cornell.meshes) {
    api::MeshData data;
    data.name = mesh.name;
    data.positions = {&mesh.positions.data()->x, mesh.positions.size() * 3};
    data.indices = {reinterpret_cast<const uint32_t*>(mesh.indices.data()),
                    mesh.indices.size() * 3};
    if (!mesh.normals.empty()) data.normals = {&mesh.normals.data()->x, mesh.normals.size() * 3};
    if (!mesh.uvs.empty()) data.uvs = {&mesh.uvs.data()->x, mesh.uvs.size() * 2};
    data.material = materials[size_t(mesh.material)];
    data.arrays = api::Arrays::Borrow;
    meshes.push_back(session.addMesh(data));
  }
  std::vector<int> objects;
  for (const Object& object : cornell.objects) {
    std::vector<int> ids;
    for (int32_t m : object.meshes) ids.push_back(meshes[size_t(m)]);
    objects.push_back(session.addObject(ids));
  }
  for (const Instance& instance : cornell.instances) {
    api::Transform t;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) t[size_t(4 * r + c)] = instance.transform.l[r][c];
      t[size_t(4 * r + 3)] = instance.transform.t[r];
    }
    session.addInstance(objects[size_t(instance.object)], t);
  }
  for (const SunLight& sun : cornell.suns)
    session.addSun({sun.direction.x, sun.direction.y, sun.direction.z},
                   {sun.irradiance.x, sun.irradiance.y, sun.irradiance.z});
  const Vec3f sky = cornell.environment.color;
  session.setEnvironment({sky.x, sky.y, sky.z});
  const CameraView& v = cornell.views[0];
  session.setCamera(
      {{v.from.x, v.from.y, v.from.z}, {v.at.x, v.at.y, v.at.z}, {v.up.x, v.up.y, v.up.z}, v.fovY});
  return session.render(2);
}

TEST(ApiSession, ASceneFromMemoryRendersTheFilesImage) {
  const Scene cornell = loadScene("builtin:cornell");
  ASSERT_TRUE(cornell.suns.empty() && !cornell.environment.image);
  api::Session session(smallOptions());
  const api::Image fromMemory = cornellFromMemory(session, cornell);
  EXPECT_EQ(rgbOf(fromMemory), rgbOf(api::render("builtin:cornell", smallOptions(), 2)));
  // A new camera renders again without reloading.
  session.setCamera({{278, 273, -500}, {278, 273, 0}, {0, 1, 0}, 50});
  const api::Image closer = session.render(1);
  EXPECT_EQ(closer.width, 48);
  EXPECT_NE(rgbOf(closer), rgbOf(fromMemory));
}

TEST(ApiSession, InProcessRanksRenderTheOneRankImage) {
  api::Options o = smallOptions();
  const api::Image alone = api::render("builtin:cornell", o, 1);
  for (int ranks : {2, 3}) {
    o.imageOnEveryRank = ranks == 3;
    std::mutex mutex;
    std::vector<api::Image> images(static_cast<size_t>(ranks));
    runRanks(ranks, [&](const Communicator& comm) {
      api::Session session = sessionOn(comm, nullptr, o);
      EXPECT_EQ(session.size(), ranks);
      session.load("builtin:cornell");
      api::Image image = session.render(1);
      std::lock_guard lock(mutex);
      images[size_t(comm.rank())] = std::move(image);
    });
    EXPECT_EQ(rgbOf(images[0]), rgbOf(alone)) << ranks << " ranks";
    for (int r = 1; r < ranks; ++r)
      if (o.imageOnEveryRank)
        EXPECT_EQ(rgbOf(images[size_t(r)]), rgbOf(alone)) << "rank " << r;
      else
        EXPECT_TRUE(images[size_t(r)].empty()) << "rank " << r;
  }
}

// AOVs by name (the "aov" setting): each an array of its channels, the same
// on 1 rank and 3 (on every rank with imageOnEveryRank, named but empty on
// the others without), written into an .exr as channels and beside a .pfm
// as files; the colour is the one without AOVs.
TEST(ApiSession, AovsComeBackByNameTheSameOnAnyRankCount) {
  api::Options o = smallOptions();
  const api::Image plain = api::render("builtin:cornell", o, 1);
  o.settings["aov"] = "albedo,normal,depth";
  const api::Image alone = api::render("builtin:cornell", o, 1);
  EXPECT_EQ(rgbOf(alone), rgbOf(plain));
  ASSERT_EQ(alone.aovs.size(), 3u);
  const api::Aov* albedo = alone.aov("albedo");
  ASSERT_NE(albedo, nullptr);
  EXPECT_EQ(albedo->channelNames, (std::vector<std::string>{"Albedo.R", "Albedo.G", "Albedo.B"}));
  EXPECT_EQ(albedo->values.size(), size_t(48 * 36 * 3));
  const api::Aov* depth = alone.aov("depth");
  ASSERT_NE(depth, nullptr);
  EXPECT_EQ(depth->channels(), 1);
  EXPECT_EQ(depth->channelNames[0], "Z");
  EXPECT_EQ(alone.aov("uv"), nullptr);
  for (bool everyRank : {false, true}) {
    o.imageOnEveryRank = everyRank;
    std::mutex mutex;
    std::vector<api::Image> images(3);
    runRanks(3, [&](const Communicator& comm) {
      api::Session session = sessionOn(comm, nullptr, o);
      session.load("builtin:cornell");
      api::Image image = session.render(1);
      std::lock_guard lock(mutex);
      images[size_t(comm.rank())] = std::move(image);
    });
    for (int r = 0; r < 3; ++r) {
      const api::Image& image = images[size_t(r)];
      ASSERT_EQ(image.aovs.size(), 3u) << "rank " << r;
      for (size_t a = 0; a < 3; ++a) {
        EXPECT_EQ(image.aovs[a].name, alone.aovs[a].name);
        if (r == 0 || everyRank)
          EXPECT_TRUE(image.aovs[a].values == alone.aovs[a].values)
              << image.aovs[a].name << ", rank " << r;
        else
          EXPECT_TRUE(image.aovs[a].values.empty()) << "rank " << r;
      }
    }
  }
  const std::string dir = ::testing::TempDir();
  api::writeImage(dir + "aovs.pfm", alone);
  for (const char* name : {"albedo", "normal", "depth"})
    EXPECT_TRUE(std::filesystem::exists(api::aovFilePath(dir + "aovs.pfm", name))) << name;
  EXPECT_EQ(api::aovFilePath("out/a.b.pfm", "albedo"), "out/a.b.albedo.pfm");
  api::writeImage(dir + "aovs.exr", alone);
  EXPECT_THROW(api::writeImage(dir + "aovs.png", alone), api::Error);
  o.settings["aov"] = "albedo,shadow";
  EXPECT_THROW(api::render("builtin:cornell", o, 1), api::Error);
}

// Each rank hands over only its own instances of the cornell box (instance i
// on rank i % ranks): the image equals one rank rendering the box assembled
// in rank order (so that the emitters come in the same order).
void addPieceOf(api::Session& session, const Scene& cornell, int rank, int ranks) {
  for (const Material& material : cornell.materials) {
    api::MaterialData data;
    data.color = {material.baseColor.x, material.baseColor.y, material.baseColor.z};
    data.emission = {material.emission.x, material.emission.y, material.emission.z};
    session.addMaterial(data);
  }
  for (size_t i = 0; i < cornell.instances.size(); ++i) {
    if (int(i % size_t(ranks)) != rank) continue;
    const Instance& instance = cornell.instances[i];
    std::vector<int> ids;
    for (int32_t m : cornell.objects[size_t(instance.object)].meshes) {
      const Mesh& mesh = cornell.meshes[size_t(m)];
      api::MeshData data;
      data.positions = {&mesh.positions.data()->x, mesh.positions.size() * 3};
      data.indices = {reinterpret_cast<const uint32_t*>(mesh.indices.data()),
                      mesh.indices.size() * 3};
      data.material = mesh.material + 1;
      data.arrays = api::Arrays::Borrow;
      ids.push_back(session.addMesh(data));
    }
    api::Transform t;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) t[size_t(4 * r + c)] = instance.transform.l[r][c];
      t[size_t(4 * r + 3)] = instance.transform.t[r];
    }
    session.addInstance(session.addObject(ids), t);
  }
  const CameraView& v = cornell.views[0];
  session.setCamera(
      {{v.from.x, v.from.y, v.from.z}, {v.at.x, v.at.y, v.at.z}, {v.up.x, v.up.y, v.up.z}, v.fovY});
}

TEST(ApiSession, DataAlreadyDistributedRendersTheAssembledImage) {
  const Scene cornell = loadScene("builtin:cornell");
  for (int ranks : {2, 3}) {
    api::Session assembled(smallOptions());
    for (int r = 0; r < ranks; ++r) addPieceOf(assembled, cornell, r, ranks);
    const api::Image expected = assembled.render(1);
    api::Options o = smallOptions();
    o.distribution = api::Distribution::Distributed;
    std::mutex mutex;
    api::Image image;
    uint64_t forwarded = 0;
    runRanks(ranks, [&](const Communicator& comm) {
      api::Session session = sessionOn(comm, nullptr, o);
      addPieceOf(session, cornell, comm.rank(), ranks);
      api::Image mine = session.render(1);
      std::lock_guard lock(mutex);
      if (comm.rank() == 0) {
        image = std::move(mine);
        forwarded = session.stats().raysForwarded;
      }
    });
    EXPECT_EQ(rgbOf(image), rgbOf(expected)) << ranks << " ranks";
    EXPECT_GT(forwarded, 0u) << "the pieces did not exchange rays";
  }
}

TEST(ApiSession, ARankThatFailsFailsTheSessionOnEveryRankWithItsMessage) {
  std::atomic<int> thrown{0};
  runRanks(3, [&](const Communicator& comm) {
    api::Session session = sessionOn(comm, nullptr, smallOptions());
    session.load(comm.rank() == 1 ? "/nonexistent/scene.pbrt" : "builtin:cornell");
    try {
      session.render(1);
      ADD_FAILURE() << "rank " << comm.rank() << " rendered";
    } catch (const api::Error& e) {
      EXPECT_NE(std::string(e.what()).find("on rank 1:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.pbrt"), std::string::npos)
          << e.what();
      ++thrown;
    }
  });
  EXPECT_EQ(thrown, 3);
}

TEST(ApiSession, RefusesBadInputWithAnError) {
  api::Session session(smallOptions());
  EXPECT_NE(message([&] {
              session.addMaterial({"m", "velvet"});
            }).find("type \"velvet\""),
            std::string::npos);
  const float positions[] = {0, 0, 0, 1, 0, 0, 0, 1};
  const uint32_t indices[] = {0, 1, 2};
  api::MeshData mesh;
  mesh.name = "bad";
  mesh.positions = positions;
  mesh.indices = indices;
  EXPECT_NE(message([&] { session.addMesh(mesh); }).find("not a multiple of 3"), std::string::npos);
  const float three[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t outOfRange[] = {0, 1, 3};
  mesh.positions = three;
  mesh.indices = outOfRange;
  EXPECT_NE(message([&] { session.addMesh(mesh); }), "no error");
  EXPECT_NE(message([&] { session.addInstance(7); }).find("object 7"), std::string::npos);
  api::VolumeData volume;
  volume.dims = {2, 2, 2};
  const float values[7] = {};
  volume.values = values;
  EXPECT_NE(message([&] { session.addVolume(volume); }).find("do not match 7 values"),
            std::string::npos);
  EXPECT_NE(message([&] { session.render(0); }).find("frames 0"), std::string::npos);
  EXPECT_NE(message([] { api::render("/nonexistent.pbrt"); }).find("/nonexistent.pbrt"),
            std::string::npos);
}

// Options::settings are `ferry render`'s flags by name: they change what the
// flags change (a crop renders that part), not what must stay the same (the
// image at any forwarding, exchange or chunk size).
TEST(ApiSession, SettingsByNameAreTheCommandsFlags) {
  api::Options o = smallOptions();
  const api::Image whole = api::render("builtin:cornell", o, 1);
  o.settings = {{"forwarding", "ring"}, {"exchange", "bulk"}, {"chunk", "64"}};
  std::mutex mutex;
  api::Image image;
  runRanks(3, [&](const Communicator& comm) {
    api::Session session = sessionOn(comm, nullptr, o);
    session.load("builtin:cornell");
    api::Image mine = session.render(1);
    std::lock_guard lock(mutex);
    if (comm.rank() == 0) image = std::move(mine);
  });
  EXPECT_EQ(rgbOf(image), rgbOf(whole));
  api::Options cropped = smallOptions();
  cropped.settings = {{"crop", "0,0.5,0,1"}};
  const api::Image left = api::render("builtin:cornell", cropped, 1);
  ASSERT_EQ(left.width, o.width / 2);
  ASSERT_EQ(left.height, o.height);
  for (int y = 0; y < left.height; ++y)
    for (int x = 0; x < left.width; ++x)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(left.rgba[size_t(4 * (y * left.width + x) + k)],
                  whole.rgba[size_t(4 * (y * whole.width + x) + k)]);
  // A camera by settings is the camera setCamera gives.
  api::Options looking = smallOptions();
  looking.settings = {{"look-from", "0.2,0.5,2.5"}, {"look-at", "0,0.4,0"}, {"fov", "50"}};
  const api::Image bySettings = api::render("builtin:cornell", looking, 1);
  api::Session session(smallOptions());
  session.load("builtin:cornell");
  session.setCamera({{0.2f, 0.5f, 2.5f}, {0, 0.4f, 0}, {0, 1, 0}, 50});
  const api::Image byCall = session.render(1);
  EXPECT_EQ(rgbOf(bySettings), rgbOf(byCall));
  EXPECT_NE(rgbOf(bySettings), rgbOf(whole));
  // The thin lens likewise: by settings with the camera, or in the Camera.
  looking.settings["lens-radius"] = "0.05";
  looking.settings["focal-distance"] = "2";
  const api::Image lensBySettings = api::render("builtin:cornell", looking, 1);
  session.setCamera({{0.2f, 0.5f, 2.5f}, {0, 0.4f, 0}, {0, 1, 0}, 50, 0.05f, 2});
  const api::Image lensByCall = session.render(1);
  EXPECT_EQ(rgbOf(lensBySettings), rgbOf(lensByCall));
  EXPECT_NE(rgbOf(lensByCall), rgbOf(byCall));
  EXPECT_THROW(session.setCamera({{0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 50, -1, 2}), api::Error);
}

TEST(ApiSession, RefusesUnknownSettingsNamingThem) {
  auto message = [](std::map<std::string, std::string> settings) {
    api::Options o = smallOptions();
    o.settings = std::move(settings);
    try {
      api::Session session(o);
    } catch (const api::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({{"colour", "red"}}).find("setting \"colour\": no such setting"),
            std::string::npos);
  EXPECT_NE(message({{"spp", "4"}}).find("a field of Options"), std::string::npos);
  EXPECT_NE(message({{"output", "x.png"}}).find("no such setting"), std::string::npos);
  EXPECT_NE(message({{"forwarding", "pigeons"}}).find("--forwarding"), std::string::npos);
  EXPECT_NE(message({{"chunk", "many"}}).find("chunk"), std::string::npos);
  EXPECT_EQ(message({{"env-fallback", ""}, {"mis", "off"}}), "no error");
  EXPECT_NE(message({{"mis-heuristic", "cubic"}}).find("--mis-heuristic cubic: expected power or"),
            std::string::npos);
  EXPECT_NE(message({{"light-choice", "far"}}).find("--light-choice far: expected near or power"),
            std::string::npos);
  EXPECT_EQ(message({{"mis-heuristic", "balance"}, {"light-choice", "power"}}), "no error");
}

TEST(ApiSession, ReportsProgressOnRankZero) {
  api::Options o = smallOptions();
  o.samplesPerPixel = 3;
  std::vector<api::Progress> seen;
  o.progress = [&](const api::Progress& p) { seen.push_back(p); };
  api::Session session(o);
  session.load("builtin:cornell");
  session.prepare();
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back().stage, "load");
  EXPECT_TRUE(seen.back().finished);
  session.render(2);
  EXPECT_EQ(seen.back().stage, "render");
  EXPECT_TRUE(seen.back().finished);
  uint64_t last = 0;
  for (const api::Progress& p : seen)
    if (p.stage == "render") {
      EXPECT_EQ(p.total, 6u);
      EXPECT_GE(p.done, last);
      last = p.done;
    }
  EXPECT_EQ(last, 6u);
  EXPECT_NE(session.stats().summary.find("memory per rank"), std::string::npos);
}

TEST(ApiSession, RendersAVolumeFromMemory) {
  api::Options o = smallOptions();
  api::Session session(o);
  std::vector<float> values(8 * 8 * 8);
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) values[size_t((z * 8 + y) * 8 + x)] = float(x + y + z) / 21;
  api::VolumeData volume;
  volume.name = "ramp";
  volume.dims = {8, 8, 8};
  volume.values = values;
  volume.colorMap = "viridis";
  session.addVolume(volume);
  session.addSun({0.4f, 1, 0.6f}, {3, 3, 3});
  session.setEnvironment({0.5f, 0.5f, 0.5f});
  const api::Image image = session.render(1);
  ASSERT_EQ(image.rgba.size(), size_t(48 * 36 * 4));
  // The volume covers the middle of the image: its pixels are not the sky's.
  const size_t middle = size_t(18 * 48 + 24) * 4, corner = 0;
  EXPECT_NE(image.rgba[middle], image.rgba[corner]);
  EXPECT_GT(session.stats().raysTraced, 0u);
}

// VTK data lists its arrays with their ranges; setField renders another
// (the data read again), as --field would; an unknown name is an Error.
TEST(ApiSession, VtkDataListsItsArraysAndRendersTheOneChosen) {
  const std::string vti =
      (std::filesystem::temp_directory_path() / fmt::format("ferry-api-{}.vti", getpid())).string();
  std::string ramp, flat;
  for (int i = 0; i < 64; ++i) {
    ramp += fmt::format("{} ", i % 4);
    flat += "1 ";
  }
  std::ofstream(vti) << fmt::format(
      R"(<?xml version="1.0"?><VTKFile type="ImageData" version="0.1">
<ImageData WholeExtent="0 3 0 3 0 3" Origin="0 0 0" Spacing="1 1 1"><Piece Extent="0 3 0 3 0 3">
<PointData Scalars="ramp"><DataArray type="Float32" Name="ramp" format="ascii">{}</DataArray>
<DataArray type="Float32" Name="flat" format="ascii">{}</DataArray></PointData>
</Piece></ImageData></VTKFile>)",
      ramp, flat);
  api::Session session(smallOptions());
  session.load(vti);
  const api::Image first = session.render(1);
  std::vector<api::Field> fields = session.fields();
  ASSERT_EQ(fields.size(), 2u);
  EXPECT_EQ(fields[0].name, "ramp");
  EXPECT_TRUE(fields[0].shown);
  EXPECT_EQ(fields[0].hi, 3);
  EXPECT_EQ(fields[1].name, "flat");
  EXPECT_FALSE(fields[1].shown);
  EXPECT_THROW(session.setField("pressure"), api::Error);
  session.setField("flat");
  const api::Image second = session.render(1);
  fields = session.fields();
  ASSERT_EQ(fields.size(), 2u);
  EXPECT_TRUE(fields[1].shown);
  EXPECT_NE(first.rgba, second.rgba);
  // As a fresh session told {"field", "flat"} renders it.
  api::Options o = smallOptions();
  o.settings["field"] = "flat";
  api::Session direct(o);
  direct.load(vti);
  EXPECT_EQ(direct.render(1).rgba, second.rgba);
  std::filesystem::remove(vti);
}

// setVolumeLook restyles a volume between renders, whole or in bricks on
// several ranks: the image a session told the look from the start makes.
TEST(ApiSession, AVolumeIsRestyledBetweenRendersWholeOrInBricks) {
  std::vector<float> values(16 * 16 * 16);
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) values[size_t((z * 16 + y) * 16 + x)] = float(x + y + z) / 45;
  api::VolumeData volume;
  volume.name = "ramp";
  volume.dims = {16, 16, 16};
  volume.values = values;
  volume.colorMap = "viridis";
  for (const char* bricks : {"0", "8"}) {
    for (int ranks : {1, 2}) {
      std::vector<float> restyled, direct;
      runRanks(ranks, [&](const Communicator& comm) {
        api::Options o = smallOptions();
        o.settings["volume-bricks"] = bricks;
        api::Session session = sessionOn(comm, nullptr, o);
        session.addVolume(volume);
        session.setEnvironment({0.8f, 0.8f, 0.8f});
        const api::Image before = session.render(1);
        EXPECT_THROW(session.setVolumeLook("jet"), api::Error);
        session.setVolumeLook("inferno", 4);
        const api::Image after = session.render(1);
        if (comm.isRoot()) {
          EXPECT_NE(before.rgba, after.rgba);
          restyled = after.rgba;
        }
        o.settings["color-map"] = "inferno";
        o.settings["volume-opacity"] = "4";
        api::Session fresh = sessionOn(comm, nullptr, o);
        fresh.addVolume(volume);
        fresh.setEnvironment({0.8f, 0.8f, 0.8f});
        const api::Image told = fresh.render(1);
        if (comm.isRoot()) direct = told.rgba;
      });
      EXPECT_FALSE(restyled.empty());
      EXPECT_EQ(restyled, direct) << "bricks " << bricks << ", " << ranks << " ranks";
    }
  }
}

// Curves from memory (placeCurves): strands of Bezier segments appear in
// the picture, the same on 1 and 3 ranks; bad arrays are errors naming them.
TEST(ApiSession, RendersCurvesFromMemoryTheSameOnAnyRankCount) {
  api::Options o = smallOptions();
  auto scene = [](api::Session& session) {
    // 20 strands of 2 segments (7 control points each) across the view.
    std::vector<float> points;
    std::vector<uint32_t> indices;
    for (int s = 0; s < 20; ++s) {
      const auto first = uint32_t(points.size() / 3);
      for (int k = 0; k < 7; ++k) {
        points.insert(points.end(), {-1.0f + 0.1f * float(s), -1.0f + float(k) / 3,
                                     0.2f * std::sin(float(k + s))});
      }
      indices.push_back(first);
      indices.push_back(first + 3);
    }
    api::MaterialData hair;
    hair.color = {0.9f, 0.5f, 0.2f};
    api::CurvesData curves;
    curves.points = points;
    curves.indices = indices;
    const float width = 0.04f;
    curves.widths = std::span<const float>(&width, 1);
    curves.material = session.addMaterial(hair);
    session.placeCurves(curves);
    session.setEnvironment({0.5f, 0.5f, 0.5f});
    api::Camera camera;
    camera.from = {0, 0, 4};
    session.setCamera(camera);
  };
  api::Session alone(o);
  scene(alone);
  const api::Image one = alone.render(1);
  const size_t middle = size_t(18 * 48 + 24) * 4;
  EXPECT_NE(one.rgba[middle], 0.5f);  // not the sky
  std::mutex mutex;
  api::Image three;
  runRanks(3, [&](const Communicator& comm) {
    api::Session session = sessionOn(comm, nullptr, o);
    scene(session);
    api::Image image = session.render(1);
    std::lock_guard lock(mutex);
    if (comm.rank() == 0) three = std::move(image);
  });
  EXPECT_EQ(rgbOf(three), rgbOf(one));

  api::Session bad(o);
  const float points[12] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0};
  const uint32_t beyond[1] = {1};
  const float widths[2] = {0.1f, 0.1f};
  api::CurvesData c;
  c.name = "tuft";
  c.points = points;
  c.indices = beyond;
  c.widths = widths;
  EXPECT_NE(message([&] { bad.placeCurves(c); }).find("2 widths for 4 control points"),
            std::string::npos);
  c.widths = std::span<const float>(widths, 1);
  EXPECT_NE(message([&] { bad.placeCurves(c); }).find("needs control points up to 4"),
            std::string::npos);
  const uint32_t first[1] = {0};
  c.indices = first;
  c.type = "hairy";
  EXPECT_NE(message([&] { bad.placeCurves(c); }).find("type \"hairy\""), std::string::npos);
}

}  // namespace
}  // namespace ferry
