// A toy simulation renders its own data in situ: the even ranks of
// MPI_COMM_WORLD each make one strip of a terrain and render the whole of it
// with Ferry on a communicator of their own, each holding only its strip
// (the odd ranks go on working); the first writes the PNG.
// Usage: mpirun -np 4 in_situ [out.png]
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include <ferry/ferry_mpi.h>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  MPI_Comm renderers;  // the even ranks render; the odd ones keep simulating
  MPI_Comm_split(MPI_COMM_WORLD, rank % 2, rank, &renderers);
  int piece = 0, pieces = 1;  // this renderer's strip of the terrain's rows
  MPI_Comm_rank(renderers, &piece);
  MPI_Comm_size(renderers, &pieces);
  // A terrain of 64 x 64 cells over [-1, 1]^2; this rank makes its rows only.
  const int n = 64, rows0 = n * piece / pieces, rows1 = n * (piece + 1) / pieces;
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  for (int j = rows0; j <= rows1; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = -1 + 2.0f * i / n, z = -1 + 2.0f * j / n;
      positions.insert(positions.end(), {x, 0.25f * std::sin(6 * x) * std::cos(5 * z), z});
    }
  for (int j = 0; j < rows1 - rows0; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      indices.insert(indices.end(), {a, c, b, b, c, d});
    }
  if (rank % 2 == 0) {
    try {
      ferry::api::Options options;
      options.width = 320;
      options.height = 240;
      options.samplesPerPixel = 8;
      options.distribution = ferry::api::Distribution::Distributed;  // each holds its strip
      ferry::api::Session session = ferry::api::sessionOn(renderers, options);
      const int ground = session.addMaterial({"ground", "diffuse", {0.6f, 0.5f, 0.3f}});
      ferry::api::MeshData mesh{"terrain", positions, indices};
      mesh.material = ground;
      mesh.arrays = ferry::api::Arrays::Borrow;  // the simulation's own arrays, not copied
      session.placeMesh(mesh);
      session.addSun({0.3f, 1, 0.4f}, {3, 3, 3});
      session.setEnvironment({0.4f, 0.5f, 0.7f});
      session.setCamera({{0, 1.6f, 2.4f}, {0, 0, 0}, {0, 1, 0}, 40});
      const ferry::api::Image image = session.render(2);
      if (session.rank() == 0) {
        ferry::api::writeImage(argc > 1 ? argv[1] : "in_situ.png", image);
        std::printf(
            "in_situ: %d renderers of %d ranks, each holding its strip: %llu rays, %llu "
            "forwarded\n",
            session.size(), ranks, (unsigned long long)session.stats().raysTraced,
            (unsigned long long)session.stats().raysForwarded);
      }
    } catch (const ferry::api::Error& e) {
      std::fprintf(stderr, "in_situ: rank %d: %s\n", rank, e.what());
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
  }
  MPI_Comm_free(&renderers);
  MPI_Barrier(MPI_COMM_WORLD);  // the simulating ranks were never blocked until here
  MPI_Finalize();
}
