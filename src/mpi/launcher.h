// What an MPI launcher (mpirun, mpiexec, srun) tells the processes it starts,
// through their environment, read before MPI is started.
//
// `ferry render` or `ferry view` started by hand is one rank and does not
// start MPI at all: Open MPI's singleton start (MPI_Init without mpirun)
// discovers the machine's topology and starts a helper daemon, which takes
// longer than a small frame (docs/architecture.md, "Two communicators").
#pragma once

namespace ferry {

// True when a launcher started this process as a rank of a job (Open MPI,
// PMIx, MPICH's Hydra or PMI-2, Slurm's srun).
bool startedByMpiLauncher();

// This process's rank as the launcher numbered it; 0 when not started by one
// or when the launcher does not say.
int launcherRank();

}  // namespace ferry
