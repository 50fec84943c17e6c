#include "scene/mesh_store.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <type_traits>

#include "core/error.h"

namespace ferry {
namespace {

template <typename T>
uint64_t arrayBytes(const SharedArray<T>& v) {
  return uint64_t(v.size()) * sizeof(T);
}

// Runs `call` (pread or pwrite: fd, buffer, count, offset) until all `n`
// bytes from offset `at` are done; `failed(why)` throws.
template <typename Buffer, typename Call, typename Failed>
void transfer(Call call, int fd, Buffer* data, uint64_t n, uint64_t& at, Failed failed) {
  auto* p = reinterpret_cast<std::conditional_t<std::is_const_v<Buffer>, const char, char>*>(data);
  while (n > 0) {
    const ssize_t done = call(fd, p, n, off_t(at));
    if (done <= 0) {
      if (done < 0 && errno == EINTR) continue;
      failed(done < 0 ? std::strerror(errno) : "short transfer");
    }
    p += done;
    at += uint64_t(done);
    n -= uint64_t(done);
  }
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
    transfer(::pwrite, fd_, data, n, at, [&](const char* why) {
      throw InputError(fmt::format("{}: writing mesh '{}' to the geometry spill file failed ({})",
                                   path_, mesh.name, why));
    });
  };
  put(mesh.positions.data(), arrayBytes(mesh.positions));
  put(mesh.normals.data(), arrayBytes(mesh.normals));
  put(mesh.uvs.data(), arrayBytes(mesh.uvs));
  put(mesh.indices.data(), arrayBytes(mesh.indices));
  mesh.releaseArrays();
  mesh.stored = s;
}

Mesh MeshStore::load(const Mesh& stored) const {
  FERRY_CHECK(stored.stored.has_value());
  const StoredMesh& s = *stored.stored;
  Mesh m;
  m.name = stored.name;
  m.material = stored.material;
  m.media = stored.media;
  uint64_t at = s.offset;
  auto get = [&](void* data, uint64_t n) {
    transfer(::pread, fd_, data, n, at, [&](const char* why) {
      throw InputError(fmt::format("{}: reading mesh '{}' back from the spill file failed ({})",
                                   path_, stored.name, why));
    });
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
