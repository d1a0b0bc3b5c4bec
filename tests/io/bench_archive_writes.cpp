// Bytes the run archive writer (io/archive.hpp) writes per generation, as a function of how many
// generations the archive already holds (issue 21 item 10: the cost of one generation must not
// grow with the run's length).
//
//   bench_archive_writes [--generations N] [--population P] [--dir DIR] [--report G,G,...]
//                        [--max-growth F]
//
// Appends N synthetic generations of P individuals through the real writer into DIR/run.h5
// (genomes of 2,800 bytes and a checkpoint of 3,200 bytes per individual, the sizes of a
// quickstart run), then finishes the archive as a run does (state change). The bytes of each
// generation are the process's write(2) byte count (/proc/self/io wchar) around that
// generation's append_generation call; page cache or disk makes no difference. Prints one line
// per reported generation and the totals. With --max-growth F it exits 1 when the last
// generation costs more than F times generation 10 (a check for ctest).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "io/archive.hpp"

namespace {

using namespace softevo::io;

// write(2) bytes of this process so far.
std::uint64_t bytes_written() {
  std::ifstream in("/proc/self/io");
  std::string key;
  std::uint64_t value = 0;
  while (in >> key >> value)
    if (key == "wchar:") return value;
  std::fprintf(stderr, "bench_archive_writes: /proc/self/io has no wchar\n");
  std::exit(2);
}

// Deterministic filler bytes (a genome's bytes do not compress in HDF5 either way: no filter).
std::vector<std::uint8_t> filler(std::size_t n, std::uint64_t seed) {
  std::vector<std::uint8_t> b(n);
  std::uint64_t x = seed * 0x9e3779b97f4a7c15ULL + 1;
  for (std::uint8_t& v : b) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    v = static_cast<std::uint8_t>(x);
  }
  return b;
}

GenerationRecord synthetic_generation(std::int64_t g, int population) {
  constexpr std::size_t kGenomeBytes = 2800;
  GenerationRecord r;
  r.generation = g;
  r.component_columns = {"fitness", "distance", "status"};
  for (int i = 0; i < population; ++i) {
    const std::int64_t id = g * population + i;
    r.id.push_back(id);
    r.parent1.push_back(id - population);
    r.parent2.push_back(-1);
    r.species.push_back(i % 5);
    r.status.push_back(0);
    r.fitness.push_back(static_cast<double>(id % 97) * 0.25);
    r.voxels.push_back(60);
    r.chambers.push_back(3);
    r.wall_seconds.push_back(1.5);
    r.worker_rank.push_back(1 + i % 4);
    r.genome.push_back(filler(kGenomeBytes, static_cast<std::uint64_t>(id)));
    r.components.insert(r.components.end(), {r.fitness.back(), 1.0, 0.0});
  }
  const FitnessStats s = fitness_stats(r.fitness);
  r.best = s.best;
  r.mean = s.mean;
  r.sd = s.sd;
  r.species_count = 5;
  r.evaluations = population;
  r.eval_wall_seconds = 30.0;
  return r;
}

std::set<std::int64_t> parse_list(const std::string& text) {
  std::set<std::int64_t> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) out.insert(std::atoll(item.c_str()));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::int64_t generations = 500;
  int population = 50;
  std::string dir;
  std::set<std::int64_t> report = {0, 1, 10, 100, 250, 499};
  double max_growth = 0.0;
  // Every option takes one value: the loop steps over option and value.
  for (int i = 1; i < argc; i += 2) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (a == "--generations" && v) {
      generations = std::atoll(v);
    } else if (a == "--population" && v) {
      population = std::atoi(v);
    } else if (a == "--dir" && v) {
      dir = v;
    } else if (a == "--report" && v) {
      report = parse_list(v);
    } else if (a == "--max-growth" && v) {
      max_growth = std::atof(v);
    } else {
      std::fprintf(stderr, "bench_archive_writes: unknown or incomplete argument %s\n", a.c_str());
      return 2;
    }
  }
  if (generations < 11 || population < 1) {
    std::fprintf(stderr, "bench_archive_writes: need --generations >= 11, --population >= 1\n");
    return 2;
  }
  bool own_dir = false;
  if (dir.empty()) {
    char pattern[] = "/tmp/softevo-bench-archive-XXXXXX";
    dir = ::mkdtemp(pattern);
    own_dir = true;
  }
  const std::string path = dir + "/run.h5";
  std::filesystem::remove_all(path + ".d");
  std::filesystem::remove(path);

  RunInfo info;
  info.version = "bench";
  info.seed = 1;
  info.config_hash = "0123456789abcdef";
  info.experiment = "gait-open";
  const std::string config_text(3000, '#');
  create_archive(path, info, config_text);

  const std::vector<std::uint8_t> checkpoint_bytes =
      filler(static_cast<std::size_t>(population) * 3200, 7);
  std::uint64_t total = 0;
  std::uint64_t at_10 = 0;
  std::uint64_t last = 0;
  std::printf("%10s %16s %16s\n", "generation", "bytes_written", "archive_bytes");
  for (std::int64_t g = 0; g < generations; ++g) {
    const GenerationRecord r = synthetic_generation(g, population);
    info.generations_done = g + 1;
    const StatsRow stats{static_cast<double>(g), r.best, r.mean, r.sd, 5.0, 1.0};
    const std::uint64_t before = bytes_written();
    append_generation(path, info, r, stats, Checkpoint{g + 1, checkpoint_bytes});
    const std::uint64_t cost = bytes_written() - before;
    total += cost;
    if (g == 10) at_10 = cost;
    last = cost;
    if (report.count(g) != 0) {
      std::uintmax_t on_disk = std::filesystem::file_size(path);
      std::error_code ec;
      for (const auto& e : std::filesystem::directory_iterator(path + ".d", ec))
        on_disk += e.file_size();
      std::printf("%10lld %16llu %16llu\n", static_cast<long long>(g),
                  static_cast<unsigned long long>(cost), static_cast<unsigned long long>(on_disk));
    }
  }
  info.state = RunState::complete;
  const std::uint64_t before_finish = bytes_written();
  finish_archive(path, info);
  const std::uint64_t finish = bytes_written() - before_finish;
  std::printf(
      "total over %lld generations: %llu bytes; finishing the archive: %llu bytes; "
      "final file %llu bytes\n",
      static_cast<long long>(generations), static_cast<unsigned long long>(total),
      static_cast<unsigned long long>(finish),
      static_cast<unsigned long long>(std::filesystem::file_size(path)));
  if (own_dir) std::filesystem::remove_all(dir);
  if (max_growth > 0 && static_cast<double>(last) > max_growth * static_cast<double>(at_10)) {
    std::fprintf(stderr,
                 "bench_archive_writes: generation %lld wrote %llu bytes, more than %.2f x the "
                 "%llu bytes of generation 10\n",
                 static_cast<long long>(generations - 1), static_cast<unsigned long long>(last),
                 max_growth, static_cast<unsigned long long>(at_10));
    return 1;
  }
  return 0;
}
