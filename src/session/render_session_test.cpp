// A render session on one rank, in this process: the sink gets the images it
// asks for, of the right size and not black, a part directory's stats name
// the partitioner that made the parts, and the set-up's intervals add up to
// the first pixel.
#include "session/render_session.h"

#include <fmt/ranges.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>

#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "io/parts/part_directory.h"
#include "io/scene_loader.h"
#include "io/volumes/volume_files.h"
#include "media/volume_look.h"
#include "partition/partitioner.h"
#include "render/camera.h"
#include "scene/light_scene.h"
#include "session/session_stats.h"
#include "shapes/unstructured_volume.h"
#include "trace/reference_backend.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

// One rank, in process (no MPI in unit tests): a group of one.
const Communicator& oneRank() {
  static InProcessGroup group(1);
  return group.communicator(0);
}

class RecordingSink final : public FrameSink {
 public:
  RecordingSink(Frames frames, Pixels pixels) : frames_(frames), pixels_(pixels) {}
  Frames frames() const override { return frames_; }
  Pixels pixels() const override { return pixels_; }
  void receive(const FrameImage& image) override { images.push_back(image); }
  std::vector<FrameImage> images;

 private:
  Frames frames_;
  Pixels pixels_;
};

SessionSettings cornellSettings() {
  SessionSettings s;
  s.scene = "builtin:cornell";
  s.render.width = 40;
  s.render.height = 24;
  s.render.samplesPerPixel = 2;
  s.render.frames = 2;
  s.render.maxDepth = 3;
  s.load.warn = [](const std::string& message) { ADD_FAILURE() << message; };
  return s;
}

bool nonBlack(const std::vector<Vec3f>& pixels) {
  for (const Vec3f& p : pixels) {
    EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    if (p.x > 0 || p.y > 0 || p.z > 0) return true;
  }
  return false;
}

TEST(RenderSession, FileLikeSinkGetsOnlyTheFinalImage) {
  ASSERT_EQ(oneRank().size(), 1);
  RenderSession session(cornellSettings(), oneRank());
  RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
  int calls = 0, rendered = 0;
  const SessionReport report = session.run(sink, [&](const RenderProgress& p) {
    ++calls;
    rendered += p.rendered;
    EXPECT_LE(p.samplesDone, p.samplesPerFrame);
  });
  ASSERT_EQ(sink.images.size(), 1u);
  const FrameImage& image = sink.images[0];
  EXPECT_TRUE(image.last);
  EXPECT_EQ(image.frame, 1);
  EXPECT_EQ(image.width, 40);
  EXPECT_EQ(image.height, 24);
  ASSERT_EQ(image.linear.size(), 40u * 24u);
  EXPECT_TRUE(image.rgba.empty());
  EXPECT_TRUE(nonBlack(image.linear));

  EXPECT_EQ(rendered, 1);
  EXPECT_EQ(calls, 2 * 2 + 1);  // every sample of both frames, then once when rendered
  ASSERT_EQ(report.stats.frames.size(), 2u);
  for (const FrameStats& frame : report.stats.frames) EXPECT_EQ(frame.cameraPaths, 40u * 24u * 2u);
  EXPECT_EQ(report.pathLayout, "mask8");
  EXPECT_EQ(report.pathBytes, 36u);
  EXPECT_EQ(report.memory.estimated.size(), 1u);
  EXPECT_EQ(report.raysReceived, 0u);
  EXPECT_EQ(session.partitionerName(), "round-robin");
}

// A viewer's sink: the accumulated image after every frame, the last one the
// same as a file sink's.
TEST(RenderSession, ProgressiveSinkGetsEveryFrameAndTheSameFinalImage) {
  std::vector<Vec3f> finalOnly;
  {
    RenderSession session(cornellSettings(), oneRank());
    RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
    session.run(sink);
    ASSERT_EQ(sink.images.size(), 1u);
    finalOnly = sink.images[0].linear;
  }
  RenderSession session(cornellSettings(), oneRank());
  RecordingSink every(FrameSink::Frames::Every, FrameSink::Pixels::Linear);
  session.run(every);
  ASSERT_EQ(every.images.size(), 2u);
  EXPECT_EQ(every.images[0].frame, 0);
  EXPECT_FALSE(every.images[0].last);
  EXPECT_TRUE(nonBlack(every.images[0].linear));
  EXPECT_EQ(every.images[1].frame, 1);
  EXPECT_TRUE(every.images[1].last);
  ASSERT_EQ(every.images[1].linear.size(), finalOnly.size());
  for (size_t i = 0; i < finalOnly.size(); ++i) {
    ASSERT_EQ(every.images[1].linear[i].x, finalOnly[i].x) << i;
    ASSERT_EQ(every.images[1].linear[i].y, finalOnly[i].y) << i;
    ASSERT_EQ(every.images[1].linear[i].z, finalOnly[i].z) << i;
  }
}

TEST(RenderSession, ToneMappedSinkGetsRgba8AtTheSizeSetAfterLoading) {
  RenderSession session(cornellSettings(), oneRank());
  session.setImageSize(17, 9);
  RecordingSink sink(FrameSink::Frames::Every, FrameSink::Pixels::ToneMapped);
  session.run(sink);
  ASSERT_EQ(sink.images.size(), 2u);
  for (const FrameImage& image : sink.images) {
    EXPECT_EQ(image.width, 17);
    EXPECT_EQ(image.height, 9);
    ASSERT_EQ(image.rgba.size(), 17u * 9u * 4u);
    EXPECT_TRUE(image.linear.empty());
    bool lit = false;
    for (size_t i = 0; i < image.rgba.size(); i += 4) {
      lit = lit || image.rgba[i] || image.rgba[i + 1] || image.rgba[i + 2];
      EXPECT_EQ(image.rgba[i + 3], 255);
    }
    EXPECT_TRUE(lit);
  }
}

TEST(RenderSession, BadSettingsAreInputErrors) {
  SessionSettings unknownView = cornellSettings();
  unknownView.render.view = "nowhere";
  EXPECT_THROW(RenderSession(unknownView, oneRank()), InputError);
  SessionSettings missing = cornellSettings();
  missing.scene = "/no/such/scene.obj";
  EXPECT_THROW(RenderSession(missing, oneRank()), InputError);
  EXPECT_THROW(checkRankCount(65, PathLayout::Mask), InputError);
  EXPECT_NO_THROW(checkRankCount(65, PathLayout::Auto));
  EXPECT_THROW(checkRankCount(kMaxRanks + 1, PathLayout::Replay), InputError);
}

// The stats of a render from a part directory name the partitioner that made
// the parts (from the manifest), not the settings' on-the-fly partitioner.
TEST(RenderSession, PartDirectoryStatsNameThePartitionerThatMadeTheParts) {
  const fs::path dir =
      fs::temp_directory_path() / ("ferry-session-test-" + std::to_string(getpid()));
  fs::remove_all(dir);
  {
    Scene scene = loadScene("builtin:cornell");
    const Scene lights = lightScene(scene);
    PartitionerOptions options;
    options.partitioner = &partitionerNamed("spatial-sah");
    const Partition partition = partitionScene(scene, 1, options);
    PartDirectoryInfo info;
    info.scene = "builtin:cornell";
    info.partitioner = options.chosen().name();
    info.summary = summarize(scene).toJson();
    writePartDirectory(dir.string(), scene, partition, lights, info);
  }
  SessionSettings settings = cornellSettings();
  settings.scene = dir.string();
  settings.partitioner = &bestPartitioner();  // not used for a part directory
  RenderSession session(settings, oneRank());
  RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
  const SessionReport report = session.run(sink);
  EXPECT_EQ(session.partitionerName(), "spatial-sah");
  const nlohmann::json stats = sessionStatsJson(session, report, {"out.pfm", 1.0});
  EXPECT_EQ(stats.at("settings").at("partition"), "spatial-sah");
  EXPECT_EQ(stats.at("settings").at("output"), "out.pfm");
  EXPECT_EQ(stats.at("settings").at("retrace"), "remote");
  EXPECT_EQ(stats.at("settings").at("forwarding"), "proxies");
  EXPECT_EQ(stats.at("settings").at("instancing"), "shared");
  EXPECT_EQ(stats.at("settings").at("path_layout"), "mask8");
  ASSERT_EQ(sink.images.size(), 1u);
  EXPECT_TRUE(nonBlack(sink.images[0].linear));
  fs::remove_all(dir);
}

// Zero-copy loading: a rank rendering its part keeps the part's mesh and
// texel arrays in the file's mapping (nothing copied them on the way into
// the scene, the Embree backend or the renderer), with the spare bytes after
// the last vertex that let Embree share them too.
TEST(RenderSession, PartGeometryStaysInTheMappedPartFile) {
  const fs::path dir =
      fs::temp_directory_path() / ("ferry-session-mapped-" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string source = "builtin:island?scale=0.05";
  {
    Scene scene = loadScene(source);
    const Scene lights = lightScene(scene);
    PartitionerOptions options;
    const Partition partition = partitionScene(scene, 1, options);
    PartDirectoryInfo info;
    info.scene = source;
    info.partitioner = options.chosen().name();
    info.summary = summarize(scene).toJson();
    writePartDirectory(dir.string(), scene, partition, lights, info);
  }
  SessionSettings settings = cornellSettings();
  settings.scene = dir.string();
  RenderSession session(settings, oneRank());
  RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
  session.run(sink);
  ASSERT_EQ(sink.images.size(), 1u);
  EXPECT_TRUE(nonBlack(sink.images[0].linear));
  const Scene& scene = session.scene();
  size_t meshes = 0, textures = 0;
  for (const Mesh& m : scene.meshes) {
    if (m.positions.empty()) continue;
    ++meshes;
    EXPECT_TRUE(m.positions.isShared() && m.indices.isShared()) << m.name;
    EXPECT_TRUE(m.normals.empty() || m.normals.isShared()) << m.name;
    EXPECT_TRUE(m.uvs.empty() || m.uvs.isShared()) << m.name;
    EXPECT_TRUE(m.hasVertexSlack()) << m.name;
    EXPECT_EQ(m.positions.ownedBytes() + m.indices.ownedBytes(), 0u) << m.name;
  }
  for (const Texture& t : scene.textures)
    if (!t.rgba.empty()) {
      ++textures;
      EXPECT_TRUE(t.rgba.isShared()) << t.name;
    }
  EXPECT_GT(meshes, 10u);
  EXPECT_GT(textures, 0u);
  fs::remove_all(dir);
}

// Where the time to the first pixel went: every rank's intervals, from the
// process's start, add up to its first pixel, and the stats name them all
// (the slowest rank's too). 3 ranks in process, partitioning on the fly.
// A scene handed over in memory renders the image its file renders, on one
// rank and partitioned over three.
TEST(RenderSession, AnInMemorySceneRendersAsItsFileDoes) {
  for (int ranks : {1, 3}) {
    std::vector<std::vector<Vec3f>> images(2);
    for (int given = 0; given < 2; ++given)
      runRanks(ranks, [&](const Communicator& comm) {
        SessionSettings settings = cornellSettings();
        settings.partitioner = &bestPartitioner();
        std::unique_ptr<RenderSession> session =
            given ? std::make_unique<RenderSession>(loadScene("builtin:cornell"), settings, comm)
                  : std::make_unique<RenderSession>(settings, comm);
        RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
        session->run(sink);
        if (comm.isRoot()) images[size_t(given)] = sink.images.at(0).linear;
      });
    ASSERT_FALSE(images[0].empty());
    EXPECT_TRUE(images[0] == images[1]) << ranks << " ranks";
  }
  Scene broken = loadScene("builtin:cornell");
  broken.meshes[0].material = 1000;
  EXPECT_THROW(RenderSession(std::move(broken), cornellSettings(), oneRank()), InputError);
}

// A transfer-function volume: a ball of values over [0, 1]^3 through the
// standard transfer function (or `transfer`).
Scene volumeBall(const TransferFunction& transfer = TransferFunction::standard()) {
  const int n = 12;
  std::vector<float> v(size_t(n * n * n));
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const Vec3f p =
            (Vec3f(float(x), float(y), float(z)) + Vec3f(0.5f)) * (1.0f / n) - Vec3f(0.5f);
        v[size_t((z * n + y) * n + x)] = std::max(0.0f, 1 - 2 * length(p));
      }
  const Box3f box{{0, 0, 0}, {1, 1, 1}};
  return volumeScene("ball",
                     transferFunctionMedium("ball", std::make_shared<DensityGrid>(n, n, n, v),
                                            std::make_shared<TransferFunction>(transfer), box),
                     box);
}

// Renders the three looks of a volume (0: a scene made with the restyled
// transfer function, 1: the plain scene with `look` set, 2: the plain scene)
// on each rank count of `ranks`, by `settings` and `scene` (a given scene, or
// none: settings.scene), checking that every rank holds a restylable volume
// and that each look's image is the same on every rank count. The images, by look.
std::array<std::vector<Vec3f>, 3> volumeLookImages(
    std::initializer_list<int> ranks, const VolumeLook& look, const SessionSettings& base,
    const std::function<std::optional<Scene>(bool restyledScene)>& scene) {
  std::array<std::vector<Vec3f>, 3> images;
  for (int n : ranks)
    for (int which = 0; which < 3; ++which)
      runRanks(n, [&](const Communicator& comm) {
        SessionSettings settings = base;
        if (which == 1) settings.render.volumeLook = look;
        std::optional<Scene> given = scene(which == 0);
        RenderSession session = given ? RenderSession(std::move(*given), settings, comm)
                                      : RenderSession(settings, comm);
        EXPECT_EQ(comm.sum(uint64_t(session.hasTransferFunctionVolumes())), uint64_t(n))
            << "every rank holds a volume to restyle";
        RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
        session.run(sink);
        if (!comm.isRoot()) return;
        if (images[size_t(which)].empty())
          images[size_t(which)] = sink.images.at(0).linear;
        else
          EXPECT_TRUE(images[size_t(which)] == sink.images.at(0).linear)
              << "look " << which << ": " << n << " ranks";
      });
  return images;
}

TEST(RenderSession, AVolumeLookRestylesTheTransferFunctionOnEveryRank) {
  const VolumeLook look{4, "viridis"};
  SessionSettings settings = cornellSettings();
  settings.scene = "ball";
  settings.load.warn = {};
  const auto [restyledScene, withLook,
              plain] = volumeLookImages({1, 2}, look, settings, [&](bool restyledScene) {
    return restyledScene ? volumeBall(restyled(TransferFunction::standard(), look)) : volumeBall();
  });
  ASSERT_TRUE(nonBlack(withLook));
  EXPECT_TRUE(withLook == restyledScene);
  EXPECT_FALSE(withLook == plain);
  SessionSettings unknown = cornellSettings();
  unknown.render.volumeLook.colorMap = "jet";
  EXPECT_THROW(RenderSession(volumeBall(), unknown, oneRank()), InputError);
}

// Bricks restyled after they are made (the look applied by the session, on
// each rank to its own bricks) render what bricks made from the restyled
// transfer function render, on 1 and 3 ranks.
TEST(RenderSession, AVolumeLookRestylesBricksOnEveryRank) {
  const VolumeLook look{4, "viridis"};
  SessionSettings settings = cornellSettings();
  settings.scene = "ball";
  settings.load.warn = {};
  settings.volumeBrickVoxels = 4;
  const auto [restyledScene, withLook,
              plain] = volumeLookImages({1, 3}, look, settings, [&](bool restyledScene) {
    return restyledScene ? volumeBall(restyled(TransferFunction::standard(), look)) : volumeBall();
  });
  ASSERT_TRUE(nonBlack(withLook));
  EXPECT_TRUE(withLook == restyledScene);
  EXPECT_FALSE(withLook == plain);
}

// An unstructured volume restyled by the session (each rank its own
// clusters): the same image on 1 and 3 ranks, another than without the look.
TEST(RenderSession, AVolumeLookRestylesUnstructuredVolumes) {
  SessionSettings settings = cornellSettings();
  settings.scene = "builtin:tets?count=6000";
  const auto [loaded, withLook, plain] = volumeLookImages(
      {1, 3}, {4, "inferno"}, settings, [](bool) { return std::optional<Scene>(); });
  ASSERT_TRUE(nonBlack(withLook));
  EXPECT_FALSE(withLook == plain);
  EXPECT_TRUE(loaded == plain);  // (no restyled scene to give: the loaded one)
}

// The viewer restyles a volume: the accumulation restarts with the new look.
class VolumeControl final : public InteractiveControl {
 public:
  bool restartPending() override { return false; }
  ViewChange takeChange() override {
    ViewChange change;
    if (published.size() == 2 && !sent) {
      change.flags = ViewChange::kVolume;
      change.volumeOpacity = 0.25f;
      change.colorMap = 2;
      sent = true;
    }
    if (published.size() == 4) change.flags |= ViewChange::kQuit;
    return change;
  }
  void publish(const InteractiveFrame& frame) override {
    published.push_back({frame.accumulated, frame.settings.volumeLook});
  }
  struct Published {
    int accumulated;
    VolumeLook look;
  };
  std::vector<Published> published;
  bool sent = false;
};

TEST(RenderSession, InteractiveVolumeLookRestartsTheAccumulation) {
  SessionSettings settings = cornellSettings();
  settings.scene = "ball";
  VolumeControl control;
  RenderSession session(volumeBall(), settings, oneRank());
  session.runInteractive(&control, 10, 0);
  ASSERT_EQ(control.published.size(), 4u);
  EXPECT_EQ(control.published[1].accumulated, 2);
  EXPECT_EQ(control.published[2].accumulated, 1);
  EXPECT_EQ(control.published[2].look.colorMap, colorMapNames()[2]);
  EXPECT_EQ(control.published[2].look.opacity, 0.25f);
  EXPECT_EQ(control.published[3].accumulated, 2);
}

TEST(RenderSession, SetUpIntervalsAddUpToTheFirstPixelOnEveryRank) {
  SessionSettings settings = cornellSettings();
  settings.partitioner = &bestPartitioner();
  nlohmann::json stats;
  runRanks(3, [&](const Communicator& comm) {
    RenderSession session(settings, comm);
    EXPECT_EQ(session.setupTimes().firstPixel, 0);  // not reached yet
    RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
    const SessionReport report = session.run(sink);
    ASSERT_EQ(report.setup.size(), 3u);
    const SetupTimes& mine = report.setup[size_t(comm.rank())];
    EXPECT_EQ(mine.firstPixel, session.setupTimes().firstPixel);
    double sum = 0;
    for (const auto& field : kSetupTimes) {
      EXPECT_GE(mine.*field.member, 0) << field.key;
      if (field.member != &SetupTimes::firstPixel) sum += mine.*field.member;
    }
    EXPECT_GT(mine.load, 0);
    EXPECT_GT(mine.partition, 0);
    EXPECT_GT(mine.build, 0);
    EXPECT_NEAR(sum, mine.firstPixel, 1e-9 * std::max(1.0, mine.firstPixel));
    if (comm.isRoot()) stats = sessionStatsJson(session, report, {"out.pfm", 1.0});
  });
  const nlohmann::json& seconds = stats.at("seconds");
  for (const auto& field : kSetupTimes) {
    EXPECT_TRUE(seconds.contains(field.key)) << field.key;
    EXPECT_TRUE(seconds.at("slowest").contains(field.key)) << field.key;
  }
  EXPECT_EQ(seconds.at("total"), 1.0);
  ASSERT_EQ(seconds.at("per_rank").size(), 3u);
  EXPECT_EQ(seconds.at("per_rank")[2].at("rank"), 2);
  EXPECT_EQ(seconds.at("load"), seconds.at("per_rank")[0].at("load"));
  const size_t slowest = seconds.at("slowest").at("rank").get<size_t>();
  ASSERT_LT(slowest, 3u);
  EXPECT_EQ(seconds.at("slowest"), seconds.at("per_rank")[slowest]);
}

// Scripted like a viewer: frames accumulate; a camera change waiting while
// a frame is rendered abandons it (at its next slice) and restarts the
// accumulation; quit ends the loop. 2 ranks in process, so the slices' word
// from rank 0 is broadcast.
class ScriptedControl final : public InteractiveControl {
 public:
  // The camera moves while the 3rd frame is rendered (the session asks
  // between slices): that frame is abandoned, and the change taken next.
  bool restartPending() override {
    if (published.size() == 2 && !moved) pendingMove = true;
    return pendingMove;
  }
  ViewChange takeChange() override {
    ViewChange change;
    if (pendingMove) {
      CameraView c = camera;
      c.from = c.from + Vec3f(40, 0, 0);
      for (int i = 0; i < 3; ++i) {
        change.from[i] = c.from[i];
        change.at[i] = c.at[i];
        change.up[i] = c.up[i];
      }
      change.fovY = c.fovY;
      change.flags = ViewChange::kCamera;
      pendingMove = false;
      moved = true;
    }
    if (published.size() == 5) change.flags |= ViewChange::kQuit;
    return change;
  }
  void publish(const InteractiveFrame& frame) override {
    published.push_back({frame.accumulated, frame.abandoned, frame.camera.from.x});
    if (published.size() == 1) camera = frame.camera;
  }
  struct Published {
    int accumulated;
    uint64_t abandoned;
    float fromX;
  };
  std::vector<Published> published;
  CameraView camera;
  bool pendingMove = false, moved = false;
};

TEST(RenderSession, InteractiveAccumulatesAbandonsForAChangeAndQuits) {
  SessionSettings settings = cornellSettings();
  settings.render.width = 128;  // 4 slices a frame (slices of 4096 pixels or more)
  settings.render.height = 128;
  settings.render.samplesPerPixel = 1;
  settings.render.maxDepth = 1;
  ScriptedControl control;
  runRanks(2, [&](const Communicator& comm) {
    RenderSession session(settings, comm);
    session.runInteractive(comm.isRoot() ? &control : nullptr, 50, /*sliceSeconds=*/0);
  });
  ASSERT_EQ(control.published.size(), 5u);
  EXPECT_EQ(control.published[0].accumulated, 1);
  EXPECT_EQ(control.published[1].accumulated, 2);
  // The third frame was abandoned: the next one published is the first of
  // the moved camera, and says one frame was abandoned.
  EXPECT_EQ(control.published[2].accumulated, 1);
  EXPECT_EQ(control.published[2].abandoned, 1u);
  EXPECT_EQ(control.published[2].fromX, control.camera.from.x + 40);
  EXPECT_EQ(control.published[3].abandoned, 0u);
  EXPECT_EQ(control.published[4].accumulated, 3);
}

// Asks for a focus pick at the image's centre before the second frame and
// records each frame's focal distance; quits after three.
class FocusControl final : public InteractiveControl {
 public:
  ViewChange takeChange() override {
    ViewChange change;
    if (taken++ == 1) {
      change.flags = ViewChange::kFocus;
      change.focusX = 0.5f;
      change.focusY = 0.5f;
    }
    if (published.size() == 3) change.flags |= ViewChange::kQuit;
    return change;
  }
  bool restartPending() override { return false; }
  void publish(const InteractiveFrame& frame) override {
    published.push_back(frame.camera.focalDistance);
    accumulated.push_back(frame.accumulated);
  }
  int taken = 0;
  std::vector<float> published;
  std::vector<int> accumulated;
};

// A focus pick (the viewer's double-click) sets the focal distance to the
// nearest surface under the point, along the view axis, over every rank's
// geometry: what a trace of the whole scene finds, on 1 rank and on 3.
TEST(RenderSession, AFocusPickFocusesOnTheNearestSurfaceOverEveryRank) {
  SessionSettings settings = cornellSettings();
  settings.render.samplesPerPixel = 1;
  settings.render.maxDepth = 1;
  const Scene scene = loadScene("builtin:cornell");
  const auto whole = makeReferenceBackend(scene);
  const Camera camera(scene.views.at(0), settings.render.width, settings.render.height);
  const Vec3f direction =
      camera.direction(0.5f * float(settings.render.width), 0.5f * float(settings.render.height));
  const TraceHit hit = whole->intersect({camera.origin(), direction});
  ASSERT_TRUE(hit.valid());
  const float expected = hit.t * camera.cosToAxis(direction);
  for (int ranks : {1, 3}) {
    SCOPED_TRACE(ranks);
    FocusControl control;
    runRanks(ranks, [&](const Communicator& comm) {
      RenderSession session(settings, comm);
      session.runInteractive(comm.isRoot() ? &control : nullptr, 10, /*sliceSeconds=*/0);
    });
    ASSERT_EQ(control.published.size(), 3u);
    EXPECT_GT(std::abs(control.published[0] - expected), 1.0f);
    EXPECT_NEAR(control.published[1], expected, 1e-3f * expected);
    EXPECT_EQ(control.published[2], control.published[1]);
    EXPECT_EQ(control.accumulated, (std::vector<int>{1, 1, 2}));  // the pick restarts
  }
}

// The final linear image of `settings` rendered on `ranks` in-process ranks.
std::vector<Vec3f> renderedOn(int ranks, const SessionSettings& settings) {
  std::vector<Vec3f> image;
  runRanks(ranks, [&](const Communicator& comm) {
    RenderSession session(settings, comm);
    RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
    session.run(sink);
    if (comm.isRoot()) image = sink.images.back().linear;
  });
  return image;
}

// A ParaView .pvtu of `pieces` ASCII .vtu pieces beside it in `dir`, each
// 2 x 2 x 2 hexahedra, side by side along x, of the point array
// T = x + y / 2 + z / 4 (continuous across the seams).
std::string writePvtu(const fs::path& dir, int pieces) {
  fs::create_directories(dir);
  std::string list;
  for (int k = 0; k < pieces; ++k) {
    std::string points, values, connectivity, offsets, types;
    for (int z = 0; z < 3; ++z)
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 3; ++x) {
          const float px = float(2 * k + x), py = float(y), pz = float(z);
          points += fmt::format("{} {} {} ", px, py, pz);
          values += fmt::format("{} ", px + py / 2 + pz / 4);
        }
    auto id = [](int x, int y, int z) { return x + 3 * y + 9 * z; };
    int cell = 0;
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x, ++cell) {
          connectivity +=
              fmt::format("{} {} {} {} {} {} {} {} ", id(x, y, z), id(x + 1, y, z),
                          id(x + 1, y + 1, z), id(x, y + 1, z), id(x, y, z + 1),
                          id(x + 1, y, z + 1), id(x + 1, y + 1, z + 1), id(x, y + 1, z + 1));
          offsets += fmt::format("{} ", 8 * (cell + 1));
          types += "12 ";
        }
    std::ofstream(dir / fmt::format("piece_{}.vtu", k)) << fmt::format(
        R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid><Piece NumberOfPoints="27" NumberOfCells="8">
    <PointData Scalars="T"><DataArray type="Float32" Name="T" format="ascii">{}</DataArray></PointData>
    <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">{}</DataArray></Points>
    <Cells>
      <DataArray type="Int64" Name="connectivity" format="ascii">{}</DataArray>
      <DataArray type="Int64" Name="offsets" format="ascii">{}</DataArray>
      <DataArray type="UInt8" Name="types" format="ascii">{}</DataArray>
    </Cells>
  </Piece></UnstructuredGrid>
</VTKFile>
)",
        values, points, connectivity, offsets, types);
    list += fmt::format("    <Piece Source=\"piece_{}.vtu\"/>\n", k);
  }
  const fs::path path = dir / "data.pvtu";
  std::ofstream(path) << fmt::format(R"(<?xml version="1.0"?>
<VTKFile type="PUnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <PUnstructuredGrid GhostLevel="0">
    <PPointData Scalars="T"><PDataArray type="Float32" Name="T"/></PPointData>
    <PPoints><PDataArray type="Float32" NumberOfComponents="3"/></PPoints>
{}  </PUnstructuredGrid>
</VTKFile>
)",
                                     list);
  return path.string();
}

// A .pvtu is read piece by piece: each rank its own run of pieces, every
// piece a volume of its own normalised by the range over all of them, so the
// image is the same on any rank count, a rank with no piece included.
TEST(RenderSession, APvtuIsReadPieceByPieceAndTheImageIsTheSameOnAnyRankCount) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("ferry-pvtu-{}", getpid());
  const std::string pvtu = writePvtu(dir, 3);
  EXPECT_EQ(readPvtuPieces(pvtu).size(), 3u);
  EXPECT_EQ(pieceRanks(3, 2, 0), (std::pair<size_t, size_t>(0, 1)));
  EXPECT_EQ(pieceRanks(3, 2, 1), (std::pair<size_t, size_t>(1, 3)));
  EXPECT_EQ(pieceRanks(3, 4, 0), (std::pair<size_t, size_t>(0, 0)));
  // Loaded whole: three volumes, the first piece's values in the low part of [0, 1].
  const Scene whole = loadScene(pvtu);
  ASSERT_EQ(whole.geometries.size(), 3u);
  EXPECT_NE(whole.name.find("[0, 7.5], 3 pieces"), std::string::npos) << whole.name;
  float value = -1;
  const auto* first = dynamic_cast<const UnstructuredVolume*>(whole.geometries[0].shape.get());
  ASSERT_NE(first, nullptr);
  for (uint32_t c = 0; c < first->primitiveCount() && value < 0; ++c)
    if (!first->valueAt(c, Vec3f(1.5f, 1, 1), value)) value = -1;
  EXPECT_NEAR(value, (1.5f + 0.5f + 0.25f) / 7.5f, 1e-5f);

  SessionSettings settings;
  settings.scene = pvtu;
  settings.render.width = 32;
  settings.render.height = 24;
  settings.render.samplesPerPixel = 2;
  settings.render.maxDepth = 4;
  const std::vector<Vec3f> one = renderedOn(1, settings);
  ASSERT_FALSE(one.empty());
  const auto byRed = [](Vec3f a, Vec3f b) { return a.x < b.x; };
  EXPECT_LT(std::min_element(one.begin(), one.end(), byRed)->x,
            std::max_element(one.begin(), one.end(), byRed)->x);  // the volume is in the picture
  for (int ranks : {2, 3, 4}) {
    std::vector<Vec3f> image;
    runRanks(ranks, [&](const Communicator& comm) {
      RenderSession session(settings, comm);
      // Every rank lists the manifest's array with its range over all pieces.
      const Scene& scene = session.scene();
      EXPECT_EQ(scene.volumeField, 0) << "rank " << comm.rank();
      EXPECT_EQ(scene.volumeFields.size(), 1u) << "rank " << comm.rank();
      if (!scene.volumeFields.empty()) {
        EXPECT_EQ(scene.volumeFields[0].name, "T");
        EXPECT_EQ(scene.volumeFields[0].lo, 0);
        EXPECT_EQ(scene.volumeFields[0].hi, 7.5);
      }
      RecordingSink sink(FrameSink::Frames::Last, FrameSink::Pixels::Linear);
      session.run(sink);
      if (comm.isRoot()) image = sink.images.back().linear;
    });
    EXPECT_TRUE(image == one) << ranks << " ranks";
  }
  // A missing piece: every rank fails with the file named.
  fs::remove(dir / "piece_2.vtu");
  runRanks(2, [&](const Communicator& comm) {
    try {
      RenderSession session(settings, comm);
      ADD_FAILURE() << "rank " << comm.rank() << " went on without piece 2";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("piece_2.vtu"), std::string::npos) << e.what();
    }
  });
  fs::remove_all(dir);
}

// A .vti of n^3 points (`extent`: the points written, within the whole
// image's), density a ball plus a ripple, velocity (x/10, y/5, 0).
void writeVti(const fs::path& path, int n, std::array<int, 6> extent) {
  std::string density, velocity;
  for (int z = extent[4]; z <= extent[5]; ++z)
    for (int y = extent[2]; y <= extent[3]; ++y)
      for (int x = extent[0]; x <= extent[1]; ++x) {
        const float r = std::sqrt(float((x - n / 2) * (x - n / 2) + (y - n / 2) * (y - n / 2) +
                                        (z - n / 2) * (z - n / 2))) /
                        float(n / 2);
        density += fmt::format("{} ", std::max(0.0f, 1 - r) * 5 + 0.1f * std::sin(float(x)));
        velocity += fmt::format("{} {} 0 ", x * 0.1f, y * 0.2f);
      }
  std::string ids;  // one per cell
  for (int c = 0; c < (extent[1] - extent[0]) * (extent[3] - extent[2]) * (extent[5] - extent[4]);
       ++c)
    ids += "1 ";
  const std::string e = fmt::format("{}", fmt::join(extent, " "));
  std::ofstream(path) << fmt::format(
      R"(<?xml version="1.0"?>
<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">
<ImageData WholeExtent="{0}" Origin="0.5 -1 2" Spacing="0.25 0.25 0.5"><Piece Extent="{0}">
<PointData Scalars="density"><DataArray type="Float32" Name="density" format="ascii">{1}</DataArray>
<DataArray type="Float32" Name="velocity" NumberOfComponents="3" format="ascii">{2}</DataArray></PointData>
<CellData><DataArray type="Int32" Name="id" format="ascii">{3}</DataArray></CellData>
</Piece></ImageData></VTKFile>)",
      e, density, velocity, ids);
}

// whole.vti (n^3 points) and p.pvti: its eight pieces split at point
// `split` on each axis (sharing that point), in `dir`.
std::string writePvti(const fs::path& dir, int n, int split, int overlap = 0) {
  fs::create_directories(dir);
  writeVti(dir / "whole.vti", n, {0, n - 1, 0, n - 1, 0, n - 1});
  std::string list;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        auto range = [&](int t) {
          return t == 0 ? std::pair{0, split + overlap} : std::pair{split, n - 1};
        };
        const std::array<int, 6> e = {range(i).first,  range(i).second, range(j).first,
                                      range(j).second, range(k).first,  range(k).second};
        const std::string name = fmt::format("p_{}{}{}.vti", i, j, k);
        writeVti(dir / name, n, e);
        list += fmt::format("<Piece Extent=\"{}\" Source=\"{}\"/>\n", fmt::join(e, " "), name);
      }
  const fs::path path = dir / "p.pvti";
  std::ofstream(path) << fmt::format(
      R"(<?xml version="1.0"?>
<VTKFile type="PImageData" version="0.1" byte_order="LittleEndian">
<PImageData WholeExtent="0 {0} 0 {0} 0 {0}" GhostLevel="0" Origin="0.5 -1 2" Spacing="0.25 0.25 0.5">
<PPointData Scalars="density"><PDataArray type="Float32" Name="density"/>
<PDataArray type="Float32" Name="velocity" NumberOfComponents="3"/></PPointData>
<PCellData><PDataArray type="Int32" Name="id"/></PCellData>
{1}</PImageData></VTKFile>)",
      n - 1, list);
  return path.string();
}

// A .pvti: each piece a brick of the cells its points start, read by the
// ranks piece by piece with the neighbours' layer its lookups need; the
// same volume as the whole .vti, so the image equals the .vti bricked along
// the same cells, on any rank count; arrays listed with their ranges.
TEST(RenderSession, APvtiIsTheWholeImageInBricksOfItsPiecesOnAnyRankCount) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("ferry-pvti-{}", getpid());
  const std::string pvti = writePvti(dir, 20, 12);
  const Scene pieces = loadScene(pvti), whole = loadScene((dir / "whole.vti").string());
  ASSERT_EQ(pieces.volumeFields.size(), 2u);  // the cell array is not offered
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(pieces.volumeFields[i].name, whole.volumeFields[i].name);
    EXPECT_EQ(pieces.volumeFields[i].lo, whole.volumeFields[i].lo);
    EXPECT_EQ(pieces.volumeFields[i].hi, whole.volumeFields[i].hi);
  }
  EXPECT_EQ(pieces.volumeField, 0);
  for (const std::string field : {"", "velocity"}) {
    SessionSettings settings;
    settings.scene = (dir / "whole.vti").string();
    settings.load.field = field;
    settings.volumeBrickVoxels = 12;
    settings.render.width = 32;
    settings.render.height = 24;
    settings.render.samplesPerPixel = 2;
    const std::vector<Vec3f> reference = renderedOn(1, settings);
    settings.scene = pvti;
    for (int ranks : {1, 2, 3})
      EXPECT_TRUE(renderedOn(ranks, settings) == reference)
          << "field '" << field << "', " << ranks << " ranks";
  }
  // Errors name the file: a cell array, pieces overlapping (ghost levels), a missing piece.
  LoadOptions cells;
  cells.field = "id";
  auto refused = [&](const std::string& path, const LoadOptions& options, const std::string& what) {
    try {
      loadScene(path, options);
      ADD_FAILURE() << "no error for " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused(pvti, cells, "'id' is a cell array");
  const std::string overlapping = writePvti(dir / "overlap", 20, 12, /*overlap=*/1);
  refused(overlapping, {}, "overlap by more than their shared boundary");
  fs::remove(dir / "p_111.vti");
  refused(pvti, {}, "p_111.vti");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ferry
