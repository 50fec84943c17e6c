#include "mpi/launcher.h"

#include <cstdlib>

namespace ferry {
namespace {

// Rank variables, most specific first: Open MPI's mpirun, PMIx launchers
// (Open MPI 5, srun --mpi=pmix), MPICH's Hydra and PMI-2 (srun --mpi=pmi2),
// and Slurm itself.
constexpr const char* kRankVariables[] = {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK",
                                          "SLURM_PROCID"};
// Set by launchers that do not set a rank variable before MPI starts.
constexpr const char* kJobVariables[] = {
    "OMPI_COMM_WORLD_SIZE", "PMI_SIZE",        "PMI_FD",
    "PMIX_NAMESPACE",       "HYDI_CONTROL_FD", "MPI_LOCALNRANKS"};

}  // namespace

bool startedByMpiLauncher() {
  for (const char* name : kRankVariables)
    if (std::getenv(name)) return true;
  for (const char* name : kJobVariables)
    if (std::getenv(name)) return true;
  return false;
}

int launcherRank() {
  for (const char* name : kRankVariables)
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return 0;
}

}  // namespace ferry
