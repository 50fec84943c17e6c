// ferry::api::Session (include/ferry/ferry.h) over a RenderSession.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <set>

#include "api/session_on.h"
#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "flags/render_flags.h"
#include "io/default_lighting.h"
#include "io/images/image_io.h"
#include "io/scene_loader.h"
#include "io/volumes/volume_files.h"
#include "material/metallic_roughness.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "media/density_grid.h"
#include "media/transfer_function.h"
#include "media/volume_look.h"
#include "mpi/mpi_communicator.h"
#include "partition/partitioner.h"
#include "render/aov.h"
#include "render/frame_buffer.h"
#include "session/partitioned_scene.h"
#include "session/render_session.h"
#include "session/session_stats.h"
#include "shapes/curves.h"

namespace ferry::api {

static_assert(sizeof(ferry::Vec3f) == 3 * sizeof(float) && sizeof(Vec3i) == 3 * sizeof(int32_t) &&
              sizeof(Vec2f) == 2 * sizeof(float));

namespace {

ferry::Vec3f vec(const Vec3& v) {
  return {v[0], v[1], v[2]};
}

// A frame's AOVs, each its own array.
std::vector<Aov> aovsOf(const FrameImage& frame) {
  std::vector<Aov> out;
  const size_t pixels = size_t(frame.width) * size_t(frame.height);
  const size_t stride = size_t(aovChannelCount(frame.aovs));
  size_t offset = 0;
  for (ferry::Aov kind : frame.aovs) {
    const AovSpec& spec = aovSpec(kind);
    Aov& a = out.emplace_back();
    a.name = spec.name;
    for (int k = 0; k < spec.channels; ++k) a.channelNames.push_back(spec.channelNames[size_t(k)]);
    a.values.resize(pixels * size_t(spec.channels));
    for (size_t i = 0; i < pixels; ++i)
      for (size_t k = 0; k < size_t(spec.channels); ++k)
        a.values[i * size_t(spec.channels) + k] = frame.aovValues[i * stride + offset + k];
    offset += size_t(spec.channels);
  }
  return out;
}

// The final image, linear, as rank 0's sink receives it.
class ImageSink final : public FrameSink {
 public:
  Frames frames() const override { return Frames::Last; }
  Pixels pixels() const override { return Pixels::Linear; }
  void receive(const FrameImage& frame) override {
    if (!frame.last) return;
    image.width = frame.width;
    image.height = frame.height;
    image.rgba.resize(size_t(frame.width) * frame.height * 4);
    for (size_t i = 0; i < frame.linear.size(); ++i) {
      std::memcpy(&image.rgba[4 * i], &frame.linear[i], 3 * sizeof(float));
      image.rgba[4 * i + 3] = 1;
    }
    image.aovs = aovsOf(frame);
  }
  Image image;
};

// What the caller gave, checked: an Error naming the span.
template <typename T, typename Element>
SharedArray<T> arrayOf(std::span<const Element> values, size_t per, const char* what,
                       const std::string& mesh, const MeshData& data, bool spare) {
  if (values.size() % per != 0)
    throw Error(fmt::format("mesh \"{}\": {} has {} values, not a multiple of {}", mesh, what,
                            values.size(), per));
  const T* first = reinterpret_cast<const T*>(values.data());
  const size_t count = values.size() / per;
  if (data.arrays == Arrays::Copy) return SharedArray<T>(first, first + count);
  std::shared_ptr<const void> keeper = data.keepAlive;
  if (!keeper) keeper = std::make_shared<int>(0);  // the caller's promise: alive until the end
  return SharedArray<T>::shared(first, count, std::move(keeper), spare);
}

// Options::settings parsed by `ferry render`'s own flags, with the fields
// of Options in the flags they stand for.
RenderOptions renderFlags(const Options& options) {
  static const std::set<std::string> fields = {"size",    "spp",         "max-depth", "seed",
                                               "threads", "partitioner", "partition"};
  static const std::set<std::string> command = {"frames", "output",        "o", "stats", "quiet",
                                                "q",      "show-partition"};
  RenderOptions flags;
  CLI::App app;
  app.set_help_flag();
  addRenderingOptions(&app, flags);
  addRunOptions(&app, flags);
  std::vector<std::string> args;
  for (const auto& [name, value] : options.settings) {
    if (fields.count(name))
      throw Error(fmt::format("setting \"{}\": given by a field of Options instead", name));
    if (command.count(name) || name.empty() || name[0] == '-' ||
        !app.get_option_no_throw("--" + name))
      throw Error(
          fmt::format("setting \"{}\": no such setting (docs/library.md lists them)", name));
    args.push_back(value.empty() ? "--" + name : fmt::format("--{}={}", name, value));
  }
  std::reverse(args.begin(), args.end());  // CLI11 takes them last first
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    throw Error(fmt::format("settings: {}", e.what()));
  }
  if (options.width > 0) flags.size = fmt::format("{}x{}", options.width, options.height);
  flags.samplesPerPixel = options.samplesPerPixel;
  flags.maxDepth = options.maxDepth >= 0 ? options.maxDepth : 5;
  flags.seed = options.seed;
  flags.threads = options.threads;
  flags.partition.partitioner = options.partitioner;
  flags.quiet = true;  // progress goes to Options::progress
  flags.writesImage = false;
  return flags;
}

}  // namespace

struct Session::Impl {
  std::shared_ptr<const void> keep;  // what the communicator needs alive
  const Communicator* comm = nullptr;
  Options options;
  RenderOptions flags;         // options.settings parsed
  bool resumePending = false;  // the first render continues flags.resume
  std::string sceneName;       // load(); else the scene from memory
  ferry::Scene scene;
  std::optional<CameraView> camera;
  std::optional<RenderSession> session;  // built at the first render after a scene change
  bool lookChanged = false;              // setVolumeLook since the session was built
  Stats stats;

  Impl(const Communicator& c, std::shared_ptr<const void> k, const Options& o)
      : keep(std::move(k)), comm(&c), options(o) {
    scene.name = "memory";
    ferry::Material grey;
    grey.name = "default";
    scene.addMaterial(grey);
    check(options);
    flags = renderFlags(options);
    resumePending = !flags.resume.empty();
    try {
      // Every value checked now; a camera given by settings is the first
      // setCamera (with the lens the settings give).
      const SessionSettings s = sessionSettings(flags, *comm);
      camera = s.render.camera;
      if (camera && s.render.lensRadius) camera->lensRadius = *s.render.lensRadius;
      if (camera && s.render.focalDistance) camera->focalDistance = *s.render.focalDistance;
    } catch (const std::exception& e) {
      throw Error(e.what());
    }
  }

  static void check(const Options& o) {
    if (o.width < 0 || o.height < 0 || o.width > 16384 || o.height > 16384 ||
        (o.width == 0) != (o.height == 0))
      throw Error(fmt::format("image size {}x{}: each side 1 to 16384 (both 0: the scene's)",
                              o.width, o.height));
    if (o.samplesPerPixel < 1)
      throw Error(fmt::format("samplesPerPixel {}: must be at least 1", o.samplesPerPixel));
    if (o.maxDepth < -1) throw Error(fmt::format("maxDepth {}: must be -1 or more", o.maxDepth));
    if (o.threads < 0) throw Error(fmt::format("threads {}: must be 0 (all) or more", o.threads));
  }

  // The scene changed: the next render builds the session again.
  ferry::Scene& changing() {
    session.reset();
    return scene;
  }

  SessionSettings settings(int frames) const {
    SessionSettings s = sessionSettings(flags, *comm);
    s.scene = sceneName.empty() ? scene.name : sceneName;
    s.render.frames = frames;
    if (camera) s.render.camera = camera;
    if (comm->isRoot() && options.progress)
      s.load.progress = [report = options.progress](uint64_t done, uint64_t total,
                                                    const std::string& what) {
        Progress p;
        p.stage = "load";
        p.done = done;
        p.total = total;
        p.what = what;
        report(p);
      };
    return s;
  }

  // Builds the session (collective); an error on any rank is thrown on every rank.
  void build(int frames) {
    std::string error;
    SessionSettings s;
    ferry::Scene copy;  // the session partitions (rewrites) its own
    const bool distributed = options.distribution == Distribution::Distributed;
    try {
      s = settings(frames);
      if (sceneName.empty())
        copy = scene;
      else if (distributed)
        copy = loadScene(sceneName, s.load);  // each rank its own piece
    } catch (const std::exception& e) {
      error = e.what();
    }
    agree(error);
    const bool inMemory = sceneName.empty() || distributed;
    if (inMemory && copy.views.empty()) {
      Box3f box = copy.worldBounds();
      for (const MediumBoundary& b : copy.mediumBoundaries) box.extend(b.mesh.bounds());
      if (distributed) box = wholeBounds(box, *comm);  // the same view on every rank
      copy.views.push_back(framingView(box));
    }
    std::optional<PartitionedScene> part;
    if (distributed) {
      try {
        part = distributedPiece(std::move(copy), *comm);  // agrees on errors itself
      } catch (const std::exception& e) {
        throw Error(e.what());
      }
    }
    try {
      if (part)
        session.emplace(std::move(*part), s, *comm);
      else if (inMemory)
        session.emplace(std::move(copy), s, *comm);
      else
        session.emplace(s, *comm);
      // The scene's own size and depth where the options leave them (pbrt's Film, Integrator).
      const ferry::Scene& own = session->scene();
      if (options.width == 0 && options.height == 0 && own.filmWidth && own.filmHeight)
        session->setImageSize(*own.filmWidth, *own.filmHeight);
      if (options.maxDepth < 0 && own.integratorMaxDepth)
        session->setMaxDepth(*own.integratorMaxDepth);
      if (std::isnan(flags.maxSampleLuminance)) {
        if (own.filmMaxSampleLuminance > 0)
          session->setSampleClamp({SampleClamp::Measure::Luminance, own.filmMaxSampleLuminance});
        else if (own.filmMaxComponentValue > 0)
          session->setSampleClamp({SampleClamp::Measure::MaxComponent, own.filmMaxComponentValue});
      }
      if (flags.crop.empty() && own.filmCrop) {
        const auto& c = *own.filmCrop;
        session->setCrop({c[0], c[1], c[2], c[3]});
      }
      // A crop that holds no pixel of the image fails here, agreed.
      session->settings().render.window();
    } catch (const std::exception& e) {
      error = e.what();
      session.reset();
    }
    agree(error);
    if (comm->isRoot() && options.progress) {
      Progress p;
      p.stage = "load";
      p.done = p.total = 1;
      p.what = setupIntervalsText(session->setupTimes(), "agree");
      p.finished = true;
      options.progress(p);
    }
  }

  // Throws `error` (merged with the other ranks') on every rank if any rank has one.
  void agree(const std::string& error) {
    const std::string failure = comm->failureMessage(!error.empty(), error);
    if (!failure.empty()) {
      session.reset();
      throw Error(failure);
    }
  }

  Image render(int frames) {
    if (frames < 1) throw Error(fmt::format("frames {}: must be at least 1", frames));
    if (!session) build(frames);
    std::string error;
    try {
      session->setSamples(options.samplesPerPixel, frames);
      if (options.width > 0) session->setImageSize(options.width, options.height);
      session->setView(session->settings().render.view, camera);
      if (lookChanged) session->setVolumeLook({flags.volumeOpacity, flags.colorMap});
      lookChanged = false;
      if (resumePending && comm->isRoot()) session->resumeFrom(flags.resume);
    } catch (const std::exception& e) {
      error = e.what();
    }
    resumePending = false;
    agree(error);
    ImageSink sink;
    SessionReport report;
    try {
      report = session->run(sink, [&](const RenderProgress& r) {
        if (!options.progress) return;
        Progress p;
        p.stage = "render";
        p.done = uint64_t(r.frame) * uint64_t(r.samplesPerFrame) + uint64_t(r.samplesDone);
        p.total = uint64_t(frames) * uint64_t(options.samplesPerPixel);
        p.frame = r.frame;
        p.secondsLeft = r.secondsLeft;
        p.finished = r.rendered;
        options.progress(p);
      });
    } catch (const GroupAborted& e) {
      session.reset();
      throw Error(e.reason());  // in-process ranks: another rank failed
    } catch (const std::exception& e) {
      session.reset();
      if (comm->size() == 1) throw Error(e.what());
      // From the middle of collective work, where the other ranks cannot be
      // told: end them all (in-process ranks: each throws GroupAborted).
      try {
        comm->abortAll(e.what());
      } catch (const GroupAborted& aborted) {
        throw Error(aborted.reason());
      }
    }
    const FrameStats total = report.stats.total();
    stats.raysTraced = total.raysTraced();
    stats.raysForwarded = total.exchangeTotal().raysForwarded;
    stats.seconds = 0;
    for (const FrameStats& f : report.stats.frames) stats.seconds += f.seconds;
    uint64_t bytes[2] = {0, 0};  // owned, borrowed
    for (const ferry::Mesh& mesh : session->scene().meshes) {
      auto count = [&](const auto& array) {
        bytes[array.isShared() ? 1 : 0] += array.size() * sizeof(array[0]);
      };
      count(mesh.positions);
      count(mesh.normals);
      count(mesh.uvs);
      count(mesh.indices);
    }
    const std::vector<uint64_t> summed = comm->sum(std::span<const uint64_t>(bytes));
    stats.meshBytesOwned = summed[0];
    stats.meshBytesBorrowed = summed[1];
    stats.json = sessionStatsJson(*session, report, {"", stats.seconds}).dump(2);
    stats.summary = comm->isRoot() ? sessionSummaryText(*session, report) : std::string();
    if (options.imageOnEveryRank && comm->size() > 1) {
      int size[2] = {sink.image.width, sink.image.height};
      comm->broadcastBytes(std::as_writable_bytes(std::span(size)));
      sink.image.width = size[0];
      sink.image.height = size[1];
      sink.image.rgba.resize(size_t(size[0]) * size[1] * 4);
      comm->broadcastBytes(std::as_writable_bytes(std::span(sink.image.rgba)));
      // The AOVs the settings asked for (the same list on every rank).
      FrameImage shape;
      shape.width = size[0];
      shape.height = size[1];
      shape.aovs = session->settings().render.aovs;
      if (!comm->isRoot()) {
        shape.aovValues.resize(size_t(size[0]) * size_t(size[1]) *
                               size_t(aovChannelCount(shape.aovs)));
        sink.image.aovs = aovsOf(shape);
      }
      for (Aov& a : sink.image.aovs)
        comm->broadcastBytes(std::as_writable_bytes(std::span(a.values)));
    } else if (!comm->isRoot()) {
      // No image here: the AOVs by name, without values.
      FrameImage names;
      names.aovs = session->settings().render.aovs;
      sink.image.aovs = aovsOf(names);
    }
    return std::move(sink.image);
  }
};

struct SessionAccess {
  static Session make(const Communicator& comm, std::shared_ptr<const void> keep,
                      const Options& options) {
    return Session(std::make_unique<Session::Impl>(comm, std::move(keep), options));
  }
};

Session::Session(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Session::Session(const Options& options) {
  // This process alone: an in-process group of one (MPI is never started).
  auto alone = std::make_shared<InProcessGroup>(1);
  const Communicator& comm = alone->communicator(0);
  impl_ = std::make_unique<Impl>(comm, alone, options);
}

Session::Session(int fortranCommunicator, const Options& options) {
  std::shared_ptr<MpiCommunicator> comm;
  try {
    comm = std::make_shared<MpiCommunicator>(ApplicationCommunicator{fortranCommunicator});
  } catch (const std::exception& e) {
    throw Error(e.what());
  }
  impl_ = std::make_unique<Impl>(*comm, comm, options);
}

Session::~Session() = default;
Session::Session(Session&&) noexcept = default;
Session& Session::operator=(Session&&) noexcept = default;

int Session::rank() const {
  return impl_->comm->rank();
}
int Session::size() const {
  return impl_->comm->size();
}

void Session::load(const std::string& scene) {
  if (scene.empty()) throw Error("load: no scene named");
  impl_->changing();
  impl_->sceneName = scene;
}

int Session::addMaterial(const MaterialData& m) {
  ferry::Material material;
  material.name = m.name;
  material.baseColor = vec(m.color);
  material.emission = vec(m.emission);
  for (float v : {m.color[0], m.color[1], m.color[2], m.emission[0], m.emission[1], m.emission[2],
                  m.roughness, m.metallic, m.ior})
    if (!std::isfinite(v) || v < 0)
      throw Error(fmt::format("material \"{}\": values must be finite and not negative", m.name));
  if (m.type == "diffuse") {
    material.model = defaultMaterialModel();
  } else if (m.type == "conductor") {
    material.model = std::make_shared<ConductorModel>(m.roughness);
  } else if (m.type == "dielectric") {
    material.model = std::make_shared<DielectricModel>(m.ior, m.roughness);
  } else if (m.type == "principled") {
    MetallicRoughness surface;
    surface.metallic = std::min(m.metallic, 1.0f);
    surface.roughness = std::min(m.roughness, 1.0f);
    surface.ior = m.ior;
    material.model = modelOf(surface);
  } else {
    throw Error(fmt::format(
        "material \"{}\": type \"{}\": expected diffuse, conductor, dielectric or principled",
        m.name, m.type));
  }
  return impl_->changing().addMaterial(std::move(material));
}

int Session::addMesh(const MeshData& data) {
  ferry::Scene& scene = impl_->changing();
  ferry::Mesh mesh;
  mesh.name = data.name.empty() ? fmt::format("mesh {}", scene.meshes.size()) : data.name;
  mesh.positions =
      arrayOf<ferry::Vec3f>(data.positions, 3, "positions", mesh.name, data, data.readablePastEnd);
  mesh.indices = arrayOf<Vec3i>(data.indices, 3, "indices", mesh.name, data, false);
  mesh.normals = arrayOf<ferry::Vec3f>(data.normals, 3, "normals", mesh.name, data, false);
  mesh.uvs = arrayOf<Vec2f>(data.uvs, 2, "uvs", mesh.name, data, false);
  if (data.material < 0 || size_t(data.material) >= scene.materials.size())
    throw Error(fmt::format("mesh \"{}\": material {} (there are {})", mesh.name, data.material,
                            scene.materials.size()));
  mesh.material = data.material;
  if (const std::string problem = mesh.arrayProblem(); !problem.empty())
    throw Error(fmt::format("mesh \"{}\": {}", mesh.name, problem));
  if (data.arrays == Arrays::Copy) mesh.reserveVertexSlack();
  scene.meshes.push_back(std::move(mesh));
  return int(scene.meshes.size() - 1);
}

int Session::addObject(std::span<const int> meshes) {
  ferry::Scene& scene = impl_->changing();
  ferry::Object object;
  object.name = fmt::format("object {}", scene.objects.size());
  for (int m : meshes) {
    if (m < 0 || size_t(m) >= scene.meshes.size())
      throw Error(fmt::format("addObject: mesh {} (there are {})", m, scene.meshes.size()));
    object.meshes.push_back(m);
  }
  if (object.meshes.empty()) throw Error("addObject: no meshes");
  scene.objects.push_back(std::move(object));
  return int(scene.objects.size() - 1);
}

void Session::addInstance(int object, const Transform& t) {
  ferry::Scene& scene = impl_->changing();
  if (object < 0 || size_t(object) >= scene.objects.size())
    throw Error(fmt::format("addInstance: object {} (there are {})", object, scene.objects.size()));
  for (float v : t)
    if (!std::isfinite(v)) throw Error("addInstance: the transform is not finite");
  Affine3f transform = Affine3f::identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) transform.l[r][c] = t[size_t(4 * r + c)];
    transform.t[r] = t[size_t(4 * r + 3)];
  }
  scene.instances.push_back({object, transform});
}

int Session::placeMesh(const MeshData& mesh) {
  const int m = addMesh(mesh);
  const int object = addObject(std::span<const int>(&m, 1));
  addInstance(object);
  return m;
}

void Session::addVolume(const VolumeData& v) {
  const std::string name = v.name.empty() ? "volume" : v.name;
  const uint64_t count = uint64_t(std::max(v.dims[0], 0)) * uint64_t(std::max(v.dims[1], 0)) *
                         uint64_t(std::max(v.dims[2], 0));
  if (v.dims[0] < 1 || v.dims[1] < 1 || v.dims[2] < 1 || count != v.values.size())
    throw Error(fmt::format("volume \"{}\": dims {} x {} x {} do not match {} values", name,
                            v.dims[0], v.dims[1], v.dims[2], v.values.size()));
  const Box3f box{vec(v.lower), vec(v.upper)};
  if (!(box.lower.x < box.upper.x && box.lower.y < box.upper.y && box.lower.z < box.upper.z))
    throw Error(fmt::format("volume \"{}\": lower must be below upper on every axis", name));
  std::shared_ptr<const DensityGrid> grid;
  try {
    grid = std::make_shared<DensityGrid>(v.dims[0], v.dims[1], v.dims[2],
                                         std::vector<float>(v.values.begin(), v.values.end()));
  } catch (const std::exception& e) {
    throw Error(fmt::format("volume \"{}\": {}", name, e.what()));
  }
  Medium medium;
  if (v.colorMap.empty()) {
    medium = gridMedium(name, vec(v.sigmaA), vec(v.sigmaS), v.g, grid, Affine3f::identity(), box);
  } else {
    const auto colors = colorMap(v.colorMap);
    if (!colors) throw Error(fmt::format("volume \"{}\": no colour map \"{}\"", name, v.colorMap));
    if (!(v.opacity > 0) || !std::isfinite(v.opacity))
      throw Error(fmt::format("volume \"{}\": opacity {}: must be positive", name, v.opacity));
    TransferFunction tf = TransferFunction::standard().withColors(*colors);
    tf = tf.withScale(v.opacity * tf.scale() / maxComponent(box.size()));
    medium = transferFunctionMedium(name, grid, std::make_shared<TransferFunction>(tf), box);
  }
  ferry::Scene& scene = impl_->changing();
  scene.media.push_back(std::move(medium));
  scene.mediumBoundaries.push_back(
      {boxMesh(box, name + " box"), {int32_t(scene.media.size() - 1), kNoMedium}});
}

void Session::placeCurves(const CurvesData& c) {
  ferry::Scene& scene = impl_->changing();
  const std::string name =
      c.name.empty() ? fmt::format("curves {}", scene.geometries.size()) : c.name;
  CurveType type;
  if (!parseCurveType(c.type, type))
    throw Error(
        fmt::format("curves \"{}\": type \"{}\": expected flat, cylinder or ribbon", name, c.type));
  if (c.points.size() % 3 != 0)
    throw Error(fmt::format("curves \"{}\": {} point coordinates are not x, y, z triples", name,
                            c.points.size()));
  const size_t count = c.points.size() / 3;
  if (c.widths.size() != 1 && c.widths.size() != count)
    throw Error(fmt::format("curves \"{}\": {} widths for {} control points (one each, or one)",
                            name, c.widths.size(), count));
  if (type == CurveType::Ribbon && c.normals.size() != c.points.size())
    throw Error(fmt::format("curves \"{}\": a ribbon needs a normal per control point", name));
  if (c.material < 0 || size_t(c.material) >= scene.materials.size())
    throw Error(fmt::format("curves \"{}\": material {} (there are {})", name, c.material,
                            scene.materials.size()));
  auto point = [&](std::span<const float> a, size_t i) {
    return ferry::Vec3f(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
  };
  auto width = [&](size_t i) { return c.widths.size() == 1 ? c.widths[0] : c.widths[i]; };
  std::vector<CurveSegment> segments;
  std::vector<CurveNormals> normals;
  segments.reserve(c.indices.size());
  for (uint32_t first : c.indices) {
    if (size_t(first) + 3 >= count)
      throw Error(
          fmt::format("curves \"{}\": segment at {} needs control points up to {} "
                      "(there are {})",
                      name, first, size_t(first) + 3, count));
    CurveSegment s;
    for (size_t k = 0; k < 4; ++k) s.points[k] = point(c.points, first + k);
    s.width0 = width(first);
    s.width1 = width(first + 3);
    segments.push_back(s);
    if (type == CurveType::Ribbon)
      normals.push_back({point(c.normals, first), point(c.normals, first + 3)});
  }
  if (segments.empty()) throw Error(fmt::format("curves \"{}\": no segments", name));
  std::shared_ptr<const Shape> shape;
  try {
    shape = std::make_shared<Curves>(type, std::move(segments), std::move(normals));
  } catch (const std::exception& e) {
    throw Error(fmt::format("curves \"{}\": {}", name, e.what()));
  }
  scene.addSingleInstanceGeometry({name, c.material, std::move(shape)});
}

void Session::addSun(const Vec3& direction, const Vec3& irradiance) {
  SunLight sun;
  const ferry::Vec3f d = vec(direction);
  if (!(length(d) > 0) || !std::isfinite(length(d))) throw Error("addSun: no direction");
  sun.direction = normalize(d);
  sun.irradiance = vec(irradiance);
  impl_->changing().suns.push_back(sun);
}

void Session::setEnvironment(const Vec3& color) {
  impl_->changing().environment.color = vec(color);
}

void Session::setCamera(const Camera& c) {
  CameraView view;
  view.name = "api";
  view.from = vec(c.from);
  view.at = vec(c.at);
  view.up = vec(c.up);
  view.fovY = c.fovY;
  view.lensRadius = c.lensRadius;
  view.focalDistance = c.focalDistance;
  if (!(c.fovY > 0 && c.fovY < 180)) throw Error(fmt::format("camera fovY {}: 0 to 180", c.fovY));
  if (!(c.lensRadius >= 0 && std::isfinite(c.lensRadius)))
    throw Error(fmt::format("camera lensRadius {}: 0 or more", c.lensRadius));
  if (!(c.focalDistance > 0 && std::isfinite(c.focalDistance)))
    throw Error(fmt::format("camera focalDistance {}: positive", c.focalDistance));
  if (!(length(view.at - view.from) > 0)) throw Error("camera: from and at are the same point");
  impl_->camera = view;
}

void Session::setImageSize(int width, int height) {
  Options o = impl_->options;
  o.width = width;
  o.height = height;
  if (width < 1 || height < 1) throw Error(fmt::format("image size {}x{}", width, height));
  Impl::check(o);
  impl_->options = o;
}

void Session::setSamplesPerPixel(int samples) {
  if (samples < 1) throw Error(fmt::format("samplesPerPixel {}: must be at least 1", samples));
  impl_->options.samplesPerPixel = samples;
}

void Session::setVolumeLook(const std::string& colorMap, float opacity) {
  if (!(opacity > 0) || !std::isfinite(opacity))
    throw Error(fmt::format("volume opacity {}: expected a positive scale", opacity));
  const auto& maps = colorMapNames();
  if (!colorMap.empty() && std::find(maps.begin(), maps.end(), colorMap) == maps.end())
    throw Error(fmt::format("colour map \"{}\": expected one of {} (or \"\": each volume's own)",
                            colorMap, fmt::join(maps, ", ")));
  impl_->flags.volumeOpacity = opacity;
  impl_->flags.colorMap = colorMap;
  impl_->lookChanged = true;
}

void Session::prepare() {
  if (!impl_->session) impl_->build(1);
}

std::string Session::filmFilename() const {
  return impl_->session ? impl_->session->scene().filmFilename : std::string();
}

std::vector<Field> Session::fields() const {
  std::vector<Field> out;
  if (!impl_->session) return out;
  const ferry::Scene& scene = impl_->session->scene();
  for (size_t i = 0; i < scene.volumeFields.size(); ++i) {
    const VolumeField& f = scene.volumeFields[i];
    out.push_back({f.name, f.atCells, f.components, f.lo, f.hi, int32_t(i) == scene.volumeField});
  }
  return out;
}

void Session::setField(const std::string& name) {
  if (impl_->session) {
    const std::vector<Field> known = fields();
    std::string names;
    bool found = false;
    for (const Field& f : known) {
      names += (names.empty() ? "" : ", ") + f.name;
      found |= f.name == name;
    }
    if (!found)
      throw Error(known.empty()
                      ? fmt::format("setField \"{}\": the scene was not read from VTK data", name)
                      : fmt::format("setField \"{}\": the data holds {}", name, names));
  }
  impl_->flags.field = name;
  impl_->changing();
}

Image Session::render(int frames) {
  return impl_->render(frames);
}

const Stats& Session::stats() const {
  return impl_->stats;
}

std::string aovFilePath(const std::string& path, const std::string& aov) {
  return sideFilePath(path, aov);
}

void writeImage(const std::string& path, const Image& image, float exposure) {
  if (image.empty() || image.rgba.size() != size_t(image.width) * image.height * 4)
    throw Error(fmt::format("{}: the image is empty or its size does not match", path));
  std::vector<ferry::Vec3f> linear(size_t(image.width) * image.height);
  for (size_t i = 0; i < linear.size(); ++i)
    linear[i] = ferry::Vec3f(image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2]);
  try {
    const std::optional<ImageFormat> format = imageFormatOf(path);
    if (!format)
      throw InputError(fmt::format("{}: unknown image format (use .png, .exr or .pfm)", path));
    const size_t pixels = linear.size();
    for (const Aov& a : image.aovs)
      if (a.channels() < 1 || a.channels() > 3 || a.values.size() != pixels * size_t(a.channels()))
        throw InputError(
            fmt::format("{}: AOV \"{}\" does not match the image's size", path, a.name));
    if (*format == ImageFormat::Png) {
      if (!image.aovs.empty())
        throw InputError(fmt::format("{}: a PNG holds no AOVs (write .exr or .pfm)", path));
      ToneMapping toneMapping;
      toneMapping.exposure = exposure;
      writePng(path, image.width, image.height, toneMapToRgba8(linear, toneMapping));
    } else if (*format == ImageFormat::Exr) {
      // Each AOV channel a float channel of the same file.
      std::vector<ImageChannel> channels;
      for (const Aov& a : image.aovs)
        for (size_t k = 0; k < size_t(a.channels()); ++k) {
          ImageChannel& c = channels.emplace_back();
          c.name = a.channelNames[k];
          c.values.resize(pixels);
          for (size_t i = 0; i < pixels; ++i) c.values[i] = a.values[i * size_t(a.channels()) + k];
        }
      writeExr(path, LinearImage{image.width, image.height, std::move(linear)}, channels);
    } else {
      // PFM: the colour, and each AOV in a file beside it (out.pfm: out.albedo.pfm),
      // grey or RGB (two channels padded with a zero third).
      ferry::writeImage(path, LinearImage{image.width, image.height, std::move(linear)});
      for (const Aov& a : image.aovs) {
        const int channels = a.channels() == 1 ? 1 : 3;
        std::vector<float> values(pixels * size_t(channels), 0.0f);
        for (size_t i = 0; i < pixels; ++i)
          for (size_t k = 0; k < size_t(a.channels()); ++k)
            values[i * size_t(channels) + k] = a.values[i * size_t(a.channels()) + k];
        writePfm(aovFilePath(path, a.name), image.width, image.height, channels, values);
      }
    }
  } catch (const std::exception& e) {
    throw Error(e.what());
  }
}

Image render(const std::string& scene, const Options& options, int frames) {
  Session session(options);
  session.load(scene);
  return session.render(frames);
}

}  // namespace ferry::api

namespace ferry {

api::Session sessionOn(const Communicator& comm, std::shared_ptr<const void> keep,
                       const api::Options& options) {
  return api::SessionAccess::make(comm, std::move(keep), options);
}

}  // namespace ferry
