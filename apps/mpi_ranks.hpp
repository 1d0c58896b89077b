// `mpirun -n P isochor run SCENE` (and `srun` under Slurm): one scene on P MPI ranks (ranks.hpp,
// docs/scale.md).
#pragma once
#include "commands.hpp"

namespace isochor::cli {

// Whether this process was started by an MPI launcher (mpirun, mpiexec, srun).
bool launched_by_mpi();
// `isochor run` on the ranks of MPI_COMM_WORLD: every rank runs the scene, rank 0 writes the file
// and the progress. One rank is the program on one process.
int cmd_run_on_ranks(const RunCommand& c, int argc, char** argv);

}  // namespace isochor::cli
