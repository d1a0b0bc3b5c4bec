// Seed corpora for the fuzz targets, made at build time (nothing binary is committed):
//   make_seeds OUT_DIR CONFIG.toml...
// OUT_DIR/config: each config, alone and with --set overrides after a NUL byte;
// OUT_DIR/robot_file: a minimal open-loop robot, alone and with a "reference" section;
// OUT_DIR/archive: tiny run archives (1 and 2 generations, gait and directed columns).
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "io/archive.hpp"

namespace fs = std::filesystem;

namespace {

void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
}

std::string numbers(std::size_t n, const char* value) {
  std::string s = "[";
  for (std::size_t i = 0; i < n; ++i) s += (i ? ", " : "") + std::string(value);
  return s + "]";
}

// A 3x1x3 body with one chamber; an Elman controller of 4 hidden units.
std::string robot_json(bool with_reference) {
  std::ostringstream j;
  j << "{\n  \"format\": \"softevo.robot/1\",\n  \"name\": \"seed\",\n  \"voxel_size\": 0.01,\n"
    << "  \"lattice\": [3, 1, 3],\n  \"cells\": [10, 10, 10, 10, 11, 10, 10, 10, 10],\n"
    << "  \"controller\": {\n    \"kind\": \"elman\",\n    \"control\": \"open\",\n"
    << "    \"directed\": false,\n"
    << "    \"hidden\": 4,\n    \"outputs\": 20,\n    \"frequency\": 3.2,\n";
  j << "    \"weights_hidden\": " << numbers(8, "0.25") << ",\n"
    << "    \"bias_hidden\": " << numbers(4, "0.1") << ",\n"
    << "    \"weights_out\": " << numbers(80, "-0.5") << ",\n"
    << "    \"bias_out\": " << numbers(20, "0.3") << ",\n"
    << "    \"weights_recurrent\": " << numbers(16, "0.01") << ",\n"
    << "    \"weights_recurrent_self\": " << numbers(4, "0.2") << ",\n"
    << "    \"weights_context\": " << numbers(4, "0.3") << ",\n"
    << "    \"bias_context\": " << numbers(4, "0.4") << "\n  }";
  if (with_reference) j << ",\n  \"reference\": {\"fitness\": 1.5, \"note\": [1, {\"a\": null}]}";
  j << "\n}\n";
  return j.str();
}

softevo::io::GenerationRecord record(std::int64_t g, int n, int units,
                                     const std::vector<std::string>& columns) {
  softevo::io::GenerationRecord r;
  r.generation = g;
  r.units = units;
  r.component_columns = columns;
  for (int i = 0; i < n; ++i) {
    r.id.push_back(10 * g + i);
    r.parent1.push_back(i == 0 ? -1 : 10 * g + i - 1);
    r.parent2.push_back(-1);
    r.species.push_back(1 + i % 2);
    r.status.push_back(i == 1 ? 1 : 0);
    r.fitness.push_back(i == 1 ? 0.0 : 0.5 * i + static_cast<double>(g));
    r.voxels.push_back(20 + i);
    r.chambers.push_back(1 + i);
    r.wall_seconds.push_back(0.25 * i);
    r.worker_rank.push_back(1);
    r.genome.push_back({0x53, 0x45, static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(i)});
    for (int u = 0; u < units; ++u)
      for (std::size_t c = 0; c < columns.size(); ++c) r.components.push_back(0.125 * (i + u + c));
  }
  const softevo::io::FitnessStats s = softevo::io::fitness_stats(r.fitness);
  r.best = s.best;
  r.mean = s.mean;
  r.sd = s.sd;
  r.species_count = 2;
  r.evaluations = n * units;
  r.eval_wall_seconds = 1.0;
  return r;
}

void archive(const fs::path& path, int generations, int units,
             const std::vector<std::string>& columns) {
  softevo::io::remove_archive(path.string());  // with the segments of an earlier build
  const softevo::Config config;
  softevo::io::RunInfo info;
  info.version = "seed";
  info.git_commit = "seed";
  info.seed = 1;
  info.host = "seed";
  info.start_time = "2026-01-01T00:00:00Z";
  info.config_hash = softevo::hash_hex(softevo::config_hash(config));
  info.experiment = softevo::experiment_name(config);
  softevo::io::create_archive(path.string(), info, softevo::canonical_text(config));
  for (int g = 0; g < generations; ++g) {
    const softevo::io::GenerationRecord r = record(g, 3, units, columns);
    info.generations_done = g + 1;
    const softevo::io::StatsRow row{static_cast<double>(g), r.best, r.mean, r.sd, 2.0, 3.0};
    softevo::io::append_generation(path.string(), info, r, row,
                                   {g + 1, {1, 2, 3, 4, 5, 6, 7, static_cast<std::uint8_t>(g)}});
  }
  // Packed into one self-contained file, as a finished run leaves it: a fuzz input is one file
  // (a root alone would only reach the "segment missing" error of its external links).
  info.state = softevo::io::RunState::complete;
  info.end_time = "2026-01-01T00:01:00Z";
  softevo::io::finish_archive(path.string(), info);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: make_seeds OUT_DIR CONFIG.toml...\n";
    return 2;
  }
  try {
    const fs::path out = argv[1];
    for (const char* kind : {"config", "robot_file", "archive"}) fs::create_directories(out / kind);
    for (int i = 2; i < argc; ++i) {
      std::ifstream in(argv[i], std::ios::binary);
      std::stringstream text;
      text << in.rdbuf();
      const std::string name = fs::path(argv[i]).stem().string();
      write_file(out / "config" / (name + ".toml"), text.str());
      write_file(
          out / "config" / (name + "-set.toml"),
          text.str() + std::string(1, '\0') +
              "run.seed=3\nneat.pop_size=8\ntask.directions=[0.0, 90.0]\nbody.lattice=[4,4,4]");
    }
    // Near the stated limits of a config (common/config.hpp): a long number and deep nesting,
    // from which the fuzzer reaches past them (its inputs go up to 64 KiB, bootstrap.sh).
    write_file(out / "config" / "long-line.toml",
               "[run]\nseed = " + std::string(softevo::kMaxConfigLineBytes - 10, '7') + "\n");
    std::string deep = "[neat]\nactivation_options = ";
    for (int i = 0; i < softevo::kMaxConfigNesting; ++i) deep += "[";
    write_file(out / "config" / "deep.toml",
               deep + "\"sin\"" + std::string(softevo::kMaxConfigNesting, ']') + "\n");
    write_file(out / "robot_file" / "open.json", robot_json(false));
    write_file(out / "robot_file" / "open-reference.json", robot_json(true));
    archive(out / "archive" / "gait-1.h5", 1, 1, {"fitness", "distance", "status"});
    archive(out / "archive" / "directed-2.h5", 2, 2,
            {"fitness", "direction_deg", "distance", "path_length", "angle_error",
             "perpendicular_penalty", "status"});
    // Only the archives are seeds (no lock file or segment directory of the writer).
    for (const fs::path& p : fs::directory_iterator(out / "archive"))
      if (p.extension() != ".h5") fs::remove_all(p);
  } catch (const std::exception& e) {
    std::cerr << "make_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
