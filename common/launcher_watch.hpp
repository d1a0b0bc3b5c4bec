// Whether the process that launched this one (mpirun, Open MPI's orted on another node, srun's
// slurmstepd) is still there. A rank whose launcher died is an orphan: nobody forwards its
// output or signals, a new job may already be resuming its archive, and its MPI peers may be
// gone, so it must stop instead of evaluating or archiving more generations (issue 21).
//
// The kernel reparents an orphan (to init or a subreaper), so getppid() changes; that is the
// test. prctl(PR_SET_PDEATHSIG) is not used: it fires when the launcher's *thread* that forked
// the rank exits, which a multi-threaded launcher may do while alive.
//
// Only a process started by a launcher is watched (its environment says so: Open MPI's
// OMPI_COMM_WORLD_SIZE, PMIx's PMIX_RANK, MPICH's PMI_SIZE, Slurm's SLURM_STEP_ID): a singleton
// `softevo-mpi` started from a shell that then exits (nohup, a closed terminal) keeps running.
#pragma once

#include <string>

namespace softevo {

// Records the current parent once (the first call; later calls do nothing). Call it early in
// main, before the launcher could have died.
void watch_launcher();
// True once the parent recorded by watch_launcher() is no longer this process's parent.
// Cheap (one getppid()); false when nothing is watched.
bool launcher_gone();
// "its launcher (pid 812) is gone" for messages; "" while the launcher is there.
std::string launcher_gone_reason();

}  // namespace softevo
