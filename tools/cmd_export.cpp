// `softevo export RUN.h5 --generation G --best -o robot.json` (or --id ID): one archived
// individual as a `softevo.robot/1` file. The body is re-developed from the archived genome with
// the archived config (record inputs, not outputs: ARCHITECTURE.md section 1). --best takes the
// highest fitness of the generation, the lowest id winning ties (§8.1 step 5: first wins).
#include <cstdio>
#include <memory>
#include <string>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "evo/genome.hpp"
#include "io/archive.hpp"
#include "tools/commands.hpp"
#include "worker/evaluate.hpp"

namespace softevo::cli {

void register_export(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("export", "write an archived individual as a robot file");
  struct Args {
    std::string path;
    std::int64_t generation = -1;
    bool best = false;
    std::int64_t id = -1;
    std::string out;
    bool force = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("RUN", a->path, "run archive (.h5)")->required();
  cmd->add_option("--generation,-g", a->generation,
                  "generation (default: the last archived generation)");
  auto* best = cmd->add_flag("--best", a->best, "the best individual of the generation");
  auto* id = cmd->add_option("--id", a->id, "the individual with this genome id");
  best->excludes(id);
  cmd->add_option("-o,--out", a->out, "output robot file (.json)")->required();
  cmd->add_flag("--force", a->force, "replace an existing output file");
  cmd->callback([&exit_code, a] {
    if (!a->best && a->id < 0) {
      std::fprintf(stderr, "softevo export: give --best or --id ID\n");
      exit_code = kExitUsage;
      return;
    }
    const io::Archive archive(a->path);
    const std::vector<std::int64_t> gens = archive.generations();
    if (gens.empty()) throw io::ArchiveError(a->path + ": no evaluated generation");
    const std::int64_t g = a->generation >= 0 ? a->generation : gens.back();
    const io::GenerationRecord rec = archive.generation(g);
    std::size_t row = rec.size();
    for (std::size_t i = 0; i < rec.size(); ++i) {
      if (a->best ? (row == rec.size() || rec.fitness[i] > rec.fitness[row]) : rec.id[i] == a->id)
        row = i;
    }
    if (row == rec.size())
      throw io::ArchiveError(a->path + ": generation " + std::to_string(g) +
                                 " has no individual with id " + std::to_string(a->id));
    const Config config = parse_config(archive.config_text(), a->path + ":/config");
    const evo::Genome genome = evo::decode_genome(rec.genome[row]);
    const std::string name = archive.info().experiment + "_seed" +
                             std::to_string(archive.info().seed) + "_gen" + std::to_string(g) +
                             "_id" + std::to_string(rec.id[row]);
    write_robot_file(worker::robot_file_of(config, genome, name), a->out,
                     a->force ? Overwrite::replace : Overwrite::refuse);
    std::printf("%s: generation %lld, id %lld, fitness %.17g -> %s\n", a->path.c_str(),
                static_cast<long long>(g), static_cast<long long>(rec.id[row]), rec.fitness[row],
                a->out.c_str());
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
