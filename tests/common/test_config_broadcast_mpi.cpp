// MPI: rank 0 resolves the config and broadcasts its canonical text; every rank re-parses it
// and must arrive at the same hash (what softevo-mpi does at start-up, tools/softevo_mpi.cpp).
#include <gtest/gtest.h>
#include <mpi.h>

#include "common/config.hpp"
#include "mpi/communicator.hpp"

namespace softevo {

TEST(ConfigBroadcast, EveryRankGetsTheSameConfigAndHash) {
  int rank = 0, size = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  ASSERT_GE(size, 2);
  std::string text;
  if (rank == 0) {
    text = canonical_text(parse_config("[run]\nseed = 5\n", "bcast.toml", {"neat.pop_size=12"}));
  }
  const std::string received = mpi::Communicator(MPI_COMM_WORLD).broadcast(text);
  const Config config = parse_config(received, "broadcast");
  EXPECT_EQ(config.run.seed, 5);
  EXPECT_EQ(config.neat.pop_size, 12);
  unsigned long long hash = config_hash(config), root_hash = hash;
  MPI_Bcast(&root_hash, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  EXPECT_EQ(hash, root_hash) << "rank " << rank;
  unsigned long long min_hash = 0, max_hash = 0;
  MPI_Allreduce(&hash, &min_hash, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(&hash, &max_hash, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_EQ(min_hash, max_hash);
}

}  // namespace softevo
