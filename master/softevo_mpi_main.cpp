// softevo-mpi: the SPMD program. Rank 0 is the master, ranks 1..N-1 are workers; with a single
// rank the master evaluates by itself. Start-up: rank 0 resolves the config (file + overrides)
// and broadcasts either its canonical text or the error; every rank then agrees to go on or to
// exit non-zero, so a broken config ends all ranks within seconds with one message.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/version.hpp"

namespace {

struct Options {
  std::string config_path = "configs/quickstart.toml";
  std::vector<std::string> overrides;
};

// Broadcast a string from rank 0 (length first, then bytes).
std::string broadcast_text(const std::string& text, int rank) {
  unsigned long long size = text.size();
  MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  std::string out = rank == 0 ? text : std::string(size, '\0');
  if (size > 0) MPI_Bcast(out.data(), static_cast<int>(size), MPI_CHAR, 0, MPI_COMM_WORLD);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  Options options;
  CLI::App app{"softevo-mpi: distributed co-evolution of soft robot bodies and brains"};
  app.add_option("--config", options.config_path, "TOML config file")
      ->capture_default_str();
  app.add_option("--set", options.overrides, "override a key: section.key=value (repeatable)");
  int parse_status = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Only rank 0 prints help or the usage error; every rank exits with the same code.
    parse_status = rank == 0 ? app.exit(e) : (e.get_exit_code() == 0 ? 0 : 2);
    MPI_Finalize();
    return parse_status == 0 ? 0 : 2;
  }

  // Rank 0 resolves the config; status 0 = ok, 1 = error (text is then the message).
  int status = 0;
  std::string text;
  if (rank == 0) {
    try {
      text = softevo::canonical_text(softevo::load_config(options.config_path, options.overrides));
    } catch (const softevo::ConfigError& e) {
      status = 1;
      text = e.what();
    }
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
  text = broadcast_text(text, rank);
  if (status != 0) {
    if (rank == 0) std::fprintf(stderr, "softevo-mpi: config error: %s\n", text.c_str());
    MPI_Finalize();
    return 2;
  }
  const softevo::Config config = softevo::parse_config(text, "broadcast config");
  if (rank == 0) {
    std::printf("softevo-mpi %s (commit %s), %d rank%s\n", softevo::kVersion, softevo::kGitCommit,
                size, size == 1 ? "" : "s");
    std::printf("# config %s (hash %s)\n%s", options.config_path.c_str(),
                softevo::hash_hex(softevo::config_hash(config)).c_str(), text.c_str());
    std::fflush(stdout);
  }
  MPI_Finalize();
  return 0;
}
