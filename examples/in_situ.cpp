// A toy simulation renders its own data in situ: every rank of MPI_COMM_WORLD
// makes a strip of a terrain, the even ranks render it with Ferry on a
// communicator of their own (the odd ones go on working), and the first of
// them writes the PNG. Usage: mpirun -np 4 in_situ [out.png]
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
  // The whole terrain, 64 x 64 cells over [-1, 1]^2, as every renderer knows it.
  const int n = 64;
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = -1 + 2.0f * i / n, z = -1 + 2.0f * j / n;
      positions.insert(positions.end(), {x, 0.25f * std::sin(6 * x) * std::cos(5 * z), z});
    }
  for (int j = 0; j < n; ++j)
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
        std::printf("in_situ: %d renderers of %d ranks, %llu rays\n", session.size(), ranks,
                    (unsigned long long)session.stats().raysTraced);
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
