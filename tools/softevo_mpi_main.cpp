// softevo-mpi: the SPMD program. Rank 0 is the master, ranks 1..N-1 are workers; with a single
// rank the master evaluates by itself. Everything but MPI_Init/Finalize lives in
// tools/softevo_mpi.cpp (softevo_mpi_main), so tests can run the program in-process.
//
//   softevo-mpi --config FILE [--seed S] [--out RUN.h5] [--generations G] [--population P]
//               [--set section.key=value ...] [--resume] [--overwrite]
//
// Exit codes: 0 complete, 2 usage/config/start-up error, 75 stopped by a signal after a
// checkpoint (rerun with --resume), 1 (MPI_Abort) an unrecoverable error on some rank.
#include "mpi/communicator.hpp"
#include "tools/softevo_mpi.hpp"

int main(int argc, char** argv) {
  const softevo::mpi::Environment mpi(argc, argv);
  return softevo::softevo_mpi_main(argc, argv, mpi.world());
}
