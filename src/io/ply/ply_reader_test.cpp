#include "io/ply/ply_reader.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"
#include "io/scene_loader.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "ply";

std::string corpus(const std::string& name) {
  return (kCorpus / name).string();
}

InputError readError(const std::string& path) {
  try {
    readPly(path);
  } catch (const InputError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": expected an InputError, got: " << e.what();
    return InputError("wrong exception");
  }
  ADD_FAILURE() << path << ": read without error";
  return InputError("no exception");
}

float area(const Mesh& m) {
  double a = 0;
  for (const Vec3i& t : m.indices)
    a += 0.5 *
         length(cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]));
  return float(a);
}

// ------------------------------------------------------------------ good files

TEST(PlyReader, AsciiQuadWithNormalsAndUv) {
  Mesh m = readPly(corpus("ascii_quad.ply"));
  EXPECT_EQ(m.name, "ascii_quad");
  ASSERT_EQ(m.vertexCount(), 4u);
  ASSERT_EQ(m.triangleCount(), 2u);  // the quad split in two
  ASSERT_EQ(m.normals.size(), 4u);
  ASSERT_EQ(m.uvs.size(), 4u);
  EXPECT_FLOAT_EQ(area(m), 1.0f);
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_EQ(m.normals[v], Vec3f(0, 0, 1));
    EXPECT_FLOAT_EQ(m.uvs[v].x, m.positions[v].x);  // u = x, v = y in this file
    EXPECT_FLOAT_EQ(m.uvs[v].y, m.positions[v].y);
  }
}

void expectTetrahedron(const Mesh& m) {
  ASSERT_EQ(m.vertexCount(), 4u);
  ASSERT_EQ(m.triangleCount(), 4u);
  EXPECT_EQ(m.positions[1], Vec3f(1, 0, 0));
  EXPECT_EQ(m.positions[3], Vec3f(0, 0, 1));
  ASSERT_EQ(m.normals.size(), 4u);
  EXPECT_FLOAT_EQ(m.normals[1].x, 0.75f);  // (1, 0, 0) - 0.25, stored as doubles
  ASSERT_EQ(m.uvs.size(), 4u);             // from s and t
  EXPECT_FLOAT_EQ(m.uvs[2].x, 0.5f);
  EXPECT_FLOAT_EQ(m.uvs[2].y, 0.5f);
  EXPECT_EQ(m.indices[0].x, 0);
  EXPECT_EQ(m.indices[0].y, 2);
  EXPECT_EQ(m.indices[0].z, 1);
  EXPECT_EQ(m.indices[3].z, 3);
}

TEST(PlyReader, BinaryLittleEndianWithExtraProperties) {
  expectTetrahedron(readPly(corpus("tet_le.ply")));
}

TEST(PlyReader, BinaryBigEndianIsTheSame) {
  Mesh le = readPly(corpus("tet_le.ply"));
  Mesh be = readPly(corpus("tet_be.ply"));
  expectTetrahedron(be);
  for (size_t v = 0; v < 4; ++v) EXPECT_EQ(le.positions[v], be.positions[v]);
}

TEST(PlyReader, BigEndianQuadWithUshortCounts) {
  Mesh m = readPly(corpus("quad_be.ply"));
  ASSERT_EQ(m.triangleCount(), 2u);
  EXPECT_FLOAT_EQ(area(m), 1.0f);
  ASSERT_EQ(m.uvs.size(), 4u);
  EXPECT_FLOAT_EQ(m.uvs[2].x, 1.0f);
  EXPECT_TRUE(m.normals.empty());
}

TEST(PlyReader, ScanWithListsEdgesAndAPentagon) {
  Mesh m = readPly(corpus("scan.ply"));
  ASSERT_EQ(m.vertexCount(), 5u);
  EXPECT_EQ(m.triangleCount(), 1u + 3u);  // a triangle and a pentagon fan
  EXPECT_EQ(m.positions[4], Vec3f(0.5f, 1.5f, 0));
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.uvs.empty());
}

TEST(PlyReader, TriangleStripsWithRestart) {
  Mesh m = readPly(corpus("tristrips.ply"));
  // 0 1 2 3 (two triangles), restart, 2 3 (too short for a triangle).
  ASSERT_EQ(m.triangleCount(), 2u);
  // Both keep the strip's orientation: the same normal direction.
  auto normal = [&](const Vec3i& t) {
    return cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
  };
  EXPECT_GT(dot(normal(m.indices[0]), normal(m.indices[1])), 0);
}

TEST(PlyReader, FromMemoryStream) {
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2";  // no newline at the end: fine
  ByteStream s = ByteStream::fromMemory(text, "memory.ply");
  Mesh m = readPly(s);
  EXPECT_EQ(m.triangleCount(), 1u);
}

// A vertex-only file with a radius is particles: a sphere at each vertex.
TEST(PlyReader, VerticesWithARadiusAreParticles) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty float radius\nend_header\n"
      "0 0 0 0.5\n2 0 0 0.25\n0 3 0 1\n";
  ByteStream s = ByteStream::fromMemory(text, "atoms.ply");
  const PlyContents c = readPlyContents(s);
  EXPECT_EQ(c.mesh.triangleCount(), 0u);
  EXPECT_EQ(c.radii, (std::vector<float>{0.5f, 0.25f, 1}));
  ByteStream again = ByteStream::fromMemory(text, "atoms.ply");
  EXPECT_THROW(readPly(again), InputError);  // as a mesh (pbrt's plymesh): no faces
  const std::string bad =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty float radius\nend_header\n0 0 0 -1\n";
  ByteStream b = ByteStream::fromMemory(bad, "bad.ply");
  try {
    readPlyContents(b);
    FAIL() << "a negative radius was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 0: radius -1"), std::string::npos) << e.what();
  }
}

TEST(PlyReader, CrLfHeader) {
  std::string text =
      "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n"
      "property float z\r\nelement face 1\r\nproperty list uchar int "
      "vertex_indices\r\nend_header\r\n"
      "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n";
  ByteStream s = ByteStream::fromMemory(text, "crlf.ply");
  EXPECT_EQ(readPly(s).triangleCount(), 1u);
}

TEST(PlyReader, PlySceneHasDefaultViewAndLight) {
  Scene scene = loadScene(corpus("tet_le.ply"));
  EXPECT_EQ(scene.name, "tet_le");
  ASSERT_EQ(scene.meshes.size(), 1u);
  ASSERT_EQ(scene.instances.size(), 1u);
  ASSERT_EQ(scene.views.size(), 1u);
  EXPECT_EQ(scene.suns.size(), 1u);
  EXPECT_GT(maxComponent(scene.environment.color), 0);
  // The view looks at the mesh's centre.
  Box3f b = scene.worldBounds();
  EXPECT_NEAR(scene.views[0].at.x, b.center().x, 1e-6);
  EXPECT_GT(scene.views[0].from.z, b.upper.z);
}

TEST(PlyReader, ProgressIsReportedForLargeFiles) {
  // A binary file of ~40 MB: progress goes up and ends at the total.
  fs::path path =
      fs::temp_directory_path() / ("ferry_ply_progress_" + std::to_string(::getpid()) + ".ply");
  const int n = 3'000'000;
  {
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << n
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << n / 3
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    std::vector<float> v(size_t(3) * n);
    for (int i = 0; i < n; ++i)
      v[size_t(3 * i)] = float(i % 1000), v[size_t(3 * i + 1)] = float(i / 1000);
    out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(float)));
    for (int f = 0; f < n / 3; ++f) {
      unsigned char c = 3;
      int idx[3] = {3 * f, 3 * f + 1, 3 * f + 2};
      out.write(reinterpret_cast<const char*>(&c), 1);
      out.write(reinterpret_cast<const char*>(idx), sizeof(idx));
    }
  }
  std::vector<uint64_t> done;
  uint64_t total = 0;
  LoadOptions options;
  options.progress = [&](uint64_t d, uint64_t t, const std::string& what) {
    done.push_back(d);
    total = t;
    EXPECT_EQ(what, path.string());
  };
  Mesh m = readPly(path.string(), options);
  fs::remove(path);
  EXPECT_EQ(m.triangleCount(), uint64_t(n / 3));
  ASSERT_GE(done.size(), 10u);
  EXPECT_LE(done.size(), 110u);
  EXPECT_TRUE(std::is_sorted(done.begin(), done.end()));
  EXPECT_EQ(done.back(), total);
}

// ------------------------------------------------------------ malformed files

struct BadPly {
  std::string file;
  int line;              // 0: a binary body (no line)
  std::string contains;  // a piece of the message
};

std::ostream& operator<<(std::ostream& os, const BadPly& b) {
  return os << b.file;
}

class PlyCorpusError : public testing::TestWithParam<BadPly> {};

TEST_P(PlyCorpusError, NamesFileAndPlace) {
  const BadPly& bad = GetParam();
  InputError e = readError(corpus(bad.file));
  std::string message = e.what();
  SCOPED_TRACE(message);
  EXPECT_NE(message.find(bad.file), std::string::npos);
  if (bad.line > 0) {
    EXPECT_EQ(e.where().line, bad.line);
    EXPECT_NE(message.find(bad.file + ":" + std::to_string(bad.line) + ": "), std::string::npos);
  }
  EXPECT_NE(message.find(bad.contains), std::string::npos) << "expected: " << bad.contains;
}

const std::vector<BadPly> kBadPly = {
    {"empty.ply", 1, "empty file"},
    {"not_ply.ply", 1, "not a PLY file"},
    {"no_end_header.ply", 7, "no end_header"},
    {"bad_format.ply", 2, "unknown format 'binary_middle_endian'"},
    {"unknown_type.ply", 4, "unknown type 'float128'"},
    {"float_count.ply", 8, "list count type 'float' is not an integer type"},
    {"missing_z.ply", 3, "vertex element has no x, y and z properties"},
    {"no_faces.ply", 0, "no faces"},
    {"index_out_of_range.ply", 14, "face 1: vertex index 7 out of range (3 vertices)"},
    {"nan_vertex.ply", 11, "vertex 1: position (1, nan, 0) is not finite"},
    {"garbage_number.ply", 11, "vertex 1: property 'y': 'zero' is not a number"},
    {"fractional_index.ply", 13, "'1.5' is not an integer"},
    {"short_face.ply", 13, "face 0 has 2 vertices (a face needs at least 3)"},
    {"truncated_ascii.ply", 13, "file ends in face 0 of 1: truncated?"},
    {"truncated_binary.ply", 0,
     "face 2: list 'vertex_indices' claims 3 items, more than the rest of the file holds"},
    {"lying_header.ply", 3,
     "element 'vertex' with 2000000000 entries needs at least 24000000000 bytes"},
    {"huge_list.ply", 0, "face 0: list 'vertex_indices' claims 4000000000 items"},
    {"binary_nan.ply", 0, "vertex 1: position (nan, 0, 0) is not finite"},
    {"binary_bad_index.ply", 0, "face 1: vertex index 9 out of range (3 vertices)"},
};

INSTANTIATE_TEST_SUITE_P(Corpus, PlyCorpusError, testing::ValuesIn(kBadPly));

TEST(PlyReader, BinaryErrorsGiveTheByteOffset) {
  InputError e = readError(corpus("binary_bad_index.ply"));
  EXPECT_NE(std::string(e.what()).find("(byte offset "), std::string::npos) << e.what();
}

TEST(PlyReader, EveryCorpusFileIsCovered) {
  std::set<std::string> tested = {"ascii_quad.ply", "tet_le.ply", "tet_be.ply",
                                  "quad_be.ply",    "scan.ply",   "tristrips.ply"};
  for (const BadPly& b : kBadPly) tested.insert(b.file);
  for (const auto& entry : fs::directory_iterator(kCorpus))
    if (entry.path().extension() == ".ply") {
      EXPECT_TRUE(tested.count(entry.path().filename().string())) << entry.path();
    }
}

}  // namespace
}  // namespace ferry
