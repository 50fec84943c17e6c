// The `ferry` Python module: include/ferry/ferry.h for Python, numpy in and
// out, mpi4py communicators. docs/library.md has the reference.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <optional>

#include "ferry/ferry.h"

namespace py = pybind11;
using namespace ferry::api;

namespace {

template <typename T>
using Array = py::array_t<T, py::array::c_style | py::array::forcecast>;

Vec3 vec3(const std::array<float, 3>& v) {
  return v;
}

// Keeps numpy arrays alive while the session uses them; released with the
// GIL held, whichever thread drops the last reference.
std::shared_ptr<const void> keeper(std::vector<py::object> arrays) {
  auto* held = new std::vector<py::object>(std::move(arrays));
  return std::shared_ptr<const void>(held, [](const void* p) {
    py::gil_scoped_acquire gil;
    delete static_cast<const std::vector<py::object>*>(p);
  });
}

// An (N, k) array of T: borrowed as it is when it already is C-ordered T
// (no copy), else converted (a copy numpy makes, kept with the others).
template <typename T>
std::span<const T> span(const py::object& object, size_t columns, const char* what,
                        std::vector<py::object>& keep) {
  Array<T> a = Array<T>::ensure(object);
  if (!a) throw Error(std::string(what) + ": not an array of numbers");
  if (!(a.ndim() == 2 && size_t(a.shape(1)) == columns) &&
      !(a.ndim() == 1 && size_t(a.size()) % columns == 0))
    throw Error(std::string(what) + ": expected shape (N, " + std::to_string(columns) + ")");
  keep.push_back(a);
  return {a.data(), size_t(a.size())};
}

py::array_t<float> rgbOf(const Image& image) {
  py::array_t<float> out({image.height, image.width, 3});
  float* o = out.mutable_data();
  for (size_t i = 0; i < size_t(image.width) * image.height; ++i)
    std::memcpy(o + 3 * i, &image.rgba[4 * i], 3 * sizeof(float));
  return out;
}

Options options(std::optional<std::pair<int, int>> size, int spp, int maxDepth, uint32_t seed,
                int threads, const std::string& partitioner, bool imageOnEveryRank,
                const std::string& distribution, const py::dict& settings) {
  Options o;
  // Values as text, the way the command line gives them (True: "true").
  for (const auto& [name, value] : settings)
    o.settings[std::string(py::str(name))] =
        py::isinstance<py::bool_>(value) ? std::string(value.cast<bool>() ? "true" : "false")
                                         : std::string(py::str(value));
  if (distribution == "distributed")
    o.distribution = Distribution::Distributed;
  else if (distribution != "replicated")
    throw Error("distribution \"" + distribution + "\": expected replicated or distributed");
  if (size) std::tie(o.width, o.height) = *size;
  o.samplesPerPixel = spp;
  o.maxDepth = maxDepth;
  o.seed = seed;
  o.threads = threads;
  o.partitioner = partitioner;
  o.imageOnEveryRank = imageOnEveryRank;
  return o;
}

// A Session with Python's habits; `comm` an mpi4py communicator or None.
struct PySession {
  std::unique_ptr<Session> session;
  Image last;  // the last render's AOVs (its colour moved out), width and height
  PySession(const py::object& comm, const Options& o) {
    if (comm.is_none())
      session = std::make_unique<Session>(o);
    else
      session = std::make_unique<Session>(comm.attr("py2f")().cast<int>(), o);
  }
};

}  // namespace

PYBIND11_MODULE(ferry, m) {
  m.doc() = "Ferry: a data-parallel path tracer (https://github.com/ -- docs/library.md)";
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

  m.def(
      "render",
      [](const std::string& scene, std::optional<std::pair<int, int>> size, int spp, uint32_t seed,
         int frames, int maxDepth, int threads, const py::dict& settings) {
        const Options o =
            options(size, spp, maxDepth, seed, threads, "", false, "replicated", settings);
        Image image;
        {
          py::gil_scoped_release release;
          image = render(scene, o, frames);
        }
        return rgbOf(image);
      },
      py::arg("scene"), py::arg("size") = py::none(), py::arg("spp") = 1, py::arg("seed") = 1,
      py::arg("frames") = 1, py::arg("max_depth") = -1, py::arg("threads") = 0,
      py::arg("settings") = py::dict(),
      "Renders a scene (a file or builtin:NAME) on this process; returns an (H, W, 3) float32 "
      "array of linear radiance. size=(W, H); default the scene's, else 1280 x 720. settings: "
      "any other flag of `ferry render` by name, as {\"forwarding\": \"ring\"}.");

  m.def(
      "write_image",
      [](const std::string& path, const py::object& rgb, float exposure) {
        Array<float> a = Array<float>::ensure(rgb);
        if (!a || a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4))
          throw Error("write_image: expected an (H, W, 3) array");
        Image image;
        image.height = int(a.shape(0));
        image.width = int(a.shape(1));
        const size_t channels = size_t(a.shape(2));
        image.rgba.assign(size_t(image.width) * image.height * 4, 1.0f);
        for (size_t i = 0; i < size_t(image.width) * image.height; ++i)
          for (size_t k = 0; k < 3; ++k) image.rgba[4 * i + k] = a.data()[channels * i + k];
        writeImage(path, image, exposure);
      },
      py::arg("path"), py::arg("image"), py::arg("exposure") = 0.0f,
      "Writes an (H, W, 3) image: .png (tone mapped as ferry render does), .exr or .pfm.");

  py::class_<PySession>(m, "Session")
      .def(py::init([](const py::object& comm, std::optional<std::pair<int, int>> size, int spp,
                       uint32_t seed, int maxDepth, int threads, const std::string& partitioner,
                       bool imageOnEveryRank, const std::string& distribution,
                       const py::dict& settings) {
             return std::make_unique<PySession>(
                 comm, options(size, spp, maxDepth, seed, threads, partitioner, imageOnEveryRank,
                               distribution, settings));
           }),
           py::arg("comm") = py::none(), py::arg("size") = py::none(), py::arg("spp") = 1,
           py::arg("seed") = 1, py::arg("max_depth") = -1, py::arg("threads") = 0,
           py::arg("partitioner") = "", py::arg("image_on_every_rank") = false,
           py::arg("distribution") = "replicated", py::arg("settings") = py::dict(),
           "A render session on this process (comm=None) or on the ranks of an mpi4py "
           "communicator; every rank makes the same calls. distribution: replicated (every "
           "rank gives the whole scene) or distributed (each rank its own piece). settings: any "
           "other flag of `ferry render` by name.")
      .def_property_readonly("rank", [](const PySession& s) { return s.session->rank(); })
      .def_property_readonly("size", [](const PySession& s) { return s.session->size(); })
      .def(
          "load", [](PySession& s, const std::string& scene) { s.session->load(scene); },
          py::arg("scene"))
      .def(
          "add_material",
          [](PySession& s, const std::string& name, const std::string& type,
             std::array<float, 3> color, std::array<float, 3> emission, float roughness,
             float metallic, float ior) {
            MaterialData d;
            d.name = name;
            d.type = type;
            d.color = vec3(color);
            d.emission = vec3(emission);
            d.roughness = roughness;
            d.metallic = metallic;
            d.ior = ior;
            return s.session->addMaterial(d);
          },
          py::arg("name") = "", py::arg("type") = "diffuse",
          py::arg("color") = std::array<float, 3>{0.8f, 0.8f, 0.8f},
          py::arg("emission") = std::array<float, 3>{0, 0, 0}, py::arg("roughness") = 0.0f,
          py::arg("metallic") = 0.0f, py::arg("ior") = 1.5f)
      .def(
          "add_mesh",
          [](PySession& s, const py::object& positions, const py::object& indices,
             const py::object& normals, const py::object& uvs, int material,
             const std::string& name, bool copy) {
            std::vector<py::object> keep;
            MeshData d;
            d.name = name;
            d.positions = span<float>(positions, 3, "positions", keep);
            d.indices = span<uint32_t>(indices, 3, "indices", keep);
            if (!normals.is_none()) d.normals = span<float>(normals, 3, "normals", keep);
            if (!uvs.is_none()) d.uvs = span<float>(uvs, 2, "uvs", keep);
            d.material = material;
            d.arrays = copy ? Arrays::Copy : Arrays::Borrow;
            if (!copy) d.keepAlive = keeper(std::move(keep));
            return s.session->addMesh(d);
          },
          py::arg("positions"), py::arg("indices"), py::arg("normals") = py::none(),
          py::arg("uvs") = py::none(), py::arg("material") = 0, py::arg("name") = "",
          py::arg("copy") = false,
          "A mesh, not placed: positions (N, 3) float32 and indices (M, 3) uint32 are "
          "borrowed, not copied, when they already have those types (copy=True copies).")
      .def(
          "add_object",
          [](PySession& s, const std::vector<int>& meshes) { return s.session->addObject(meshes); },
          py::arg("meshes"))
      .def(
          "add_instance",
          [](PySession& s, int object, const py::object& transform) {
            Transform t = kIdentity;
            if (!transform.is_none()) {
              Array<float> a = Array<float>::ensure(transform);
              if (!a || a.ndim() != 2 || a.shape(1) != 4 || (a.shape(0) != 3 && a.shape(0) != 4))
                throw Error("add_instance: the transform must be a 3x4 or 4x4 array");
              std::memcpy(t.data(), a.data(), sizeof(t));
            }
            s.session->addInstance(object, t);
          },
          py::arg("object"), py::arg("transform") = py::none())
      .def(
          "place_mesh",
          [](PySession& s, const py::object& positions, const py::object& indices,
             const py::object& normals, const py::object& uvs, int material,
             const std::string& name, bool copy) {
            py::object self = py::cast(&s, py::return_value_policy::reference);
            const int mesh =
                self.attr("add_mesh")(positions, indices, normals, uvs, material, name, copy)
                    .cast<int>();
            const int object = s.session->addObject(std::vector<int>{mesh});
            s.session->addInstance(object);
            return mesh;
          },
          py::arg("positions"), py::arg("indices"), py::arg("normals") = py::none(),
          py::arg("uvs") = py::none(), py::arg("material") = 0, py::arg("name") = "",
          py::arg("copy") = false, "add_mesh, placed once, untransformed.")
      .def(
          "place_curves",
          [](PySession& s, const py::object& points, const py::object& indices,
             const py::object& widths, const std::string& type, const py::object& normals,
             int material, const std::string& name) {
            std::vector<py::object> keep;
            CurvesData d;
            d.name = name;
            d.points = span<float>(points, 3, "points", keep);
            d.indices = span<uint32_t>(indices, 1, "indices", keep);
            std::vector<float> one;
            if (py::isinstance<py::float_>(widths) || py::isinstance<py::int_>(widths)) {
              one.push_back(widths.cast<float>());
              d.widths = one;
            } else {
              d.widths = span<float>(widths, 1, "widths", keep);
            }
            if (!normals.is_none()) d.normals = span<float>(normals, 3, "normals", keep);
            d.type = type;
            d.material = material;
            s.session->placeCurves(d);
          },
          py::arg("points"), py::arg("indices"), py::arg("widths"), py::arg("type") = "flat",
          py::arg("normals") = py::none(), py::arg("material") = 0, py::arg("name") = "",
          "Curves placed once: points (N, 3) float32 control points, indices (M,) uint32 (a "
          "cubic Bezier segment's first of 4 consecutive points), widths (N,) or one number; "
          "type flat, cylinder or ribbon (normals (N, 3)). Copied.")
      .def(
          "add_volume",
          [](PySession& s, const py::object& values, std::array<float, 3> lower,
             std::array<float, 3> upper, std::array<float, 3> sigmaA, std::array<float, 3> sigmaS,
             float g, const std::string& colorMap, float opacity, const std::string& name) {
            Array<float> a = Array<float>::ensure(values);
            if (!a || a.ndim() != 3)
              throw Error("add_volume: values must be an (nz, ny, nx) array");
            VolumeData d;
            d.name = name;
            d.dims = {int(a.shape(2)), int(a.shape(1)), int(a.shape(0))};
            d.values = {a.data(), size_t(a.size())};
            d.lower = lower;
            d.upper = upper;
            d.sigmaA = sigmaA;
            d.sigmaS = sigmaS;
            d.g = g;
            d.colorMap = colorMap;
            d.opacity = opacity;
            s.session->addVolume(d);
          },
          py::arg("values"), py::arg("lower") = std::array<float, 3>{0, 0, 0},
          py::arg("upper") = std::array<float, 3>{1, 1, 1},
          py::arg("sigma_a") = std::array<float, 3>{1, 1, 1},
          py::arg("sigma_s") = std::array<float, 3>{9, 9, 9}, py::arg("g") = 0.0f,
          py::arg("color_map") = "", py::arg("opacity") = 1.0f, py::arg("name") = "",
          "A density grid (nz, ny, nx), x fastest, over the box lower..upper: smoke, or "
          "drawn through a colour map (values in [0, 1]).")
      .def(
          "add_sun",
          [](PySession& s, std::array<float, 3> direction, std::array<float, 3> irradiance) {
            s.session->addSun(direction, irradiance);
          },
          py::arg("direction"), py::arg("irradiance") = std::array<float, 3>{3, 3, 3})
      .def(
          "set_environment",
          [](PySession& s, std::array<float, 3> color) { s.session->setEnvironment(color); },
          py::arg("color"))
      .def(
          "set_camera",
          [](PySession& s, std::array<float, 3> lookFrom, std::array<float, 3> lookAt,
             std::array<float, 3> up, float fov, float lensRadius, float focalDistance) {
            s.session->setCamera({lookFrom, lookAt, up, fov, lensRadius, focalDistance});
          },
          py::arg("look_from"), py::arg("look_at"), py::arg("up") = std::array<float, 3>{0, 1, 0},
          py::arg("fov") = 45.0f, py::arg("lens_radius") = 0.0f, py::arg("focal_distance") = 1e6f)
      .def(
          "set_image_size",
          [](PySession& s, int width, int height) { s.session->setImageSize(width, height); },
          py::arg("width"), py::arg("height"))
      .def(
          "set_spp", [](PySession& s, int spp) { s.session->setSamplesPerPixel(spp); },
          py::arg("spp"))
      .def(
          "set_volume_look",
          [](PySession& s, const std::string& colorMap, float opacity) {
            s.session->setVolumeLook(colorMap, opacity);
          },
          py::arg("color_map") = "", py::arg("opacity") = 1.0f,
          "Restyles the volumes drawn through a colour map (whole or in bricks), between "
          "renders without reloading: a map name (\"\": each volume's own) and an opacity scale.")
      .def(
          "fields",
          [](const PySession& s) {
            py::list out;
            for (const Field& f : s.session->fields()) {
              py::dict d;
              d["name"] = f.name;
              d["at"] = f.atCells ? "cells" : "points";
              d["components"] = f.components;
              d["range"] = py::make_tuple(f.lo, f.hi);
              d["shown"] = f.shown;
              out.append(d);
            }
            return out;
          },
          "After prepare() or render(): the arrays of the VTK data the scene was read from, "
          "each a dict (name, at, components, range, shown); empty for other scenes.")
      .def(
          "set_field", [](PySession& s, const std::string& name) { s.session->setField(name); },
          py::arg("name"),
          "Renders another array of the VTK data from the next render on (read again).")
      .def(
          "render",
          [](PySession& s, int frames) -> py::object {
            Image image;
            {
              py::gil_scoped_release release;
              image = s.session->render(frames);
            }
            s.last = Image{image.width, image.height, {}, std::move(image.aovs)};
            if (image.empty()) return py::none();
            return rgbOf(image);
          },
          py::arg("frames") = 1,
          "Renders (collective); an (H, W, 3) float32 array on rank 0 (every rank with "
          "image_on_every_rank), None elsewhere.")
      .def(
          "aov",
          [](const PySession& s, const std::string& name) -> py::object {
            const Aov* a = s.last.aov(name);
            if (!a) {
              std::string asked;
              for (const Aov& b : s.last.aovs) asked += (asked.empty() ? "" : ", ") + b.name;
              throw Error("aov \"" + name + "\": the last render wrote " +
                          (asked.empty() ? std::string("none") : asked) +
                          " (settings={\"aov\": \"albedo,normal,depth\"})");
            }
            if (a->values.empty()) return py::none();
            py::array_t<float> out({s.last.height, s.last.width, a->channels()});
            std::memcpy(out.mutable_data(), a->values.data(), a->values.size() * sizeof(float));
            return out;
          },
          py::arg("name"),
          "The last render's AOV `name` (settings={\"aov\": \"albedo,normal,depth\"}): an "
          "(H, W, C) float32 array where the image is (C: 3, depth 1, uv 2), None elsewhere.")
      .def_property_readonly("stats", [](const PySession& s) {
        const Stats& st = s.session->stats();
        py::dict d = py::module_::import("json").attr("loads")(st.json);
        d["rays_traced"] = st.raysTraced;
        d["rays_forwarded"] = st.raysForwarded;
        d["seconds"] = st.seconds;
        d["mesh_bytes_owned"] = st.meshBytesOwned;
        d["mesh_bytes_borrowed"] = st.meshBytesBorrowed;
        d["summary"] = st.summary;
        return d;
      });
}
