#include "scene/mesh_store.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace ferry {
namespace {

template <typename T>
uint64_t arrayBytes(const std::vector<T>& v) {
  return uint64_t(v.size()) * sizeof(T);
}

}  // namespace

MeshStore::MeshStore(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd_ < 0)
    throw InputError(
        fmt::format("{}: cannot create the geometry spill file ({})", path, std::strerror(errno)));
  ::unlink(path.c_str());
}

MeshStore::~MeshStore() {
  if (fd_ >= 0) ::close(fd_);
}

void MeshStore::store(Mesh& mesh) {
  if (mesh.stored) return;
  // Stored meshes skip Scene::validate's array checks: checked here instead.
  if (std::string problem = mesh.arrayProblem(); !problem.empty()) throw InputError(problem);
  StoredMesh s;
  s.vertices = mesh.positions.size();
  s.triangles = mesh.indices.size();
  s.normals = !mesh.normals.empty();
  s.uvs = !mesh.uvs.empty();
  s.bounds = mesh.bounds();
  const uint64_t bytes = arrayBytes(mesh.positions) + arrayBytes(mesh.normals) +
                         arrayBytes(mesh.uvs) + arrayBytes(mesh.indices);
  s.offset = end_.fetch_add(bytes);  // this mesh's range, reserved
  uint64_t at = s.offset;
  auto put = [&](const void* data, uint64_t n) {
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
      const ssize_t w = ::pwrite(fd_, p, n, off_t(at));
      if (w <= 0) {
        if (w < 0 && errno == EINTR) continue;
        throw InputError(fmt::format("{}: writing mesh '{}' to the geometry spill file failed ({})",
                                     path_, mesh.name, w < 0 ? std::strerror(errno) : "no space"));
      }
      p += w;
      at += uint64_t(w);
      n -= uint64_t(w);
    }
  };
  put(mesh.positions.data(), arrayBytes(mesh.positions));
  put(mesh.normals.data(), arrayBytes(mesh.normals));
  put(mesh.uvs.data(), arrayBytes(mesh.uvs));
  put(mesh.indices.data(), arrayBytes(mesh.indices));
  std::vector<Vec3f>().swap(mesh.positions);
  std::vector<Vec3f>().swap(mesh.normals);
  std::vector<Vec2f>().swap(mesh.uvs);
  std::vector<Vec3i>().swap(mesh.indices);
  mesh.stored = s;
}

Mesh MeshStore::load(const Mesh& stored) const {
  FERRY_CHECK(stored.stored.has_value());
  const StoredMesh& s = *stored.stored;
  Mesh m;
  m.name = stored.name;
  m.material = stored.material;
  uint64_t at = s.offset;
  auto get = [&](void* data, uint64_t n) {
    char* p = static_cast<char*>(data);
    while (n > 0) {
      const ssize_t r = ::pread(fd_, p, n, off_t(at));
      if (r <= 0) {
        if (r < 0 && errno == EINTR) continue;
        throw InputError(fmt::format("{}: reading mesh '{}' back from the spill file failed ({})",
                                     path_, stored.name, r < 0 ? std::strerror(errno) : "short"));
      }
      p += r;
      at += uint64_t(r);
      n -= uint64_t(r);
    }
  };
  m.positions.reserve(s.vertices + 1);  // Embree's one element of slack
  m.positions.resize(s.vertices);
  get(m.positions.data(), arrayBytes(m.positions));
  if (s.normals) {
    m.normals.resize(s.vertices);
    get(m.normals.data(), arrayBytes(m.normals));
  }
  if (s.uvs) {
    m.uvs.resize(s.vertices);
    get(m.uvs.data(), arrayBytes(m.uvs));
  }
  m.indices.resize(s.triangles);
  get(m.indices.data(), arrayBytes(m.indices));
  return m;
}

}  // namespace ferry
