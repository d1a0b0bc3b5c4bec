// `softevo export RUN.h5 [--generation G] [--best | --id ID | --cell I,J] -o robot.json [--json]`:
// one archived individual as a `softevo.robot/1` file. The body is re-developed from the archived
// genome with the archived config (record inputs, not outputs: docs/architecture.md §1). The
// default (and --best) is the highest fitness of the generation, the lowest id winning ties
// (§8.1 step 5: first wins), as for render and replay. The file's `evaluation` block carries the
// run's config, its hashes and the archived fitness and status, so that `softevo eval` gives the
// archived fitness back bit for bit (docs/model.md §10). In a run with controller learning the
// robot is the body with its learned controller, whose evaluation the archived fitness is.
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/config_identity.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "common/round_trip.hpp"
#include "evo/genome.hpp"
#include "io/archive.hpp"
#include "tools/commands.hpp"
#include "tools/elite_cell.hpp"
#include "worker/evaluate.hpp"

namespace softevo::cli {

void register_export(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("export", "write an archived individual as a robot file");
  struct Args {
    std::string path;
    std::optional<std::int64_t> generation;
    bool best = false;
    std::optional<std::int64_t> id;
    std::string cell;
    std::string out;
    bool force = false;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("RUN", a->path, "run archive (.h5)")->required();
  add_individual_options(*cmd, a->generation, a->id, a->best, &a->cell, "");
  cmd->add_option("-o,--output,--out", a->out, "output robot file (.json)")->required();
  cmd->add_flag("--force", a->force, "replace an existing output file");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->callback([&exit_code, a] {
    const io::Archive archive(a->path);
    const std::vector<std::int64_t> gens = archive.generations();
    if (gens.empty()) throw io::ArchiveError(a->path + ": no evaluated generation");
    std::int64_t g = a->generation.value_or(gens.back());
    if (!a->cell.empty()) {  // the elite's row: the generation that evaluated it
      const EliteRow elite = elite_of_cell(archive, a->cell, g);
      a->id = elite.id;
      g = elite.generation;
    }
    a->best = !a->id;
    // --id alone: the last generation that holds it (an elite stays under its id).
    if (!a->best && a->cell.empty()) g = archive.generation_of(*a->id, a->generation);
    const io::GenerationRecord rec = archive.generation(g);
    std::size_t row = rec.size();
    for (std::size_t i = 0; i < rec.size(); ++i) {
      if (a->best ? (row == rec.size() || rec.fitness[i] > rec.fitness[row]) : rec.id[i] == *a->id)
        row = i;
    }
    if (row == rec.size())
      throw io::ArchiveError(a->path + ": generation " + std::to_string(g) +
                             " has no individual with id " + std::to_string(*a->id));
    const Config config = parse_config(archive.config_text(), a->path + ":/config");
    // A learning run's fitness is its learned controller's: the learned robot is exported.
    const evo::Genome genome =
        evo::decode_genome(rec.has_learning() ? rec.learned_genome[row] : rec.genome[row]);
    const std::string name = archive.info().experiment + "_seed" +
                             std::to_string(archive.info().seed) + "_gen" + std::to_string(g) +
                             "_id" + std::to_string(rec.id[row]);
    RobotFile robot = worker::robot_file_of(config, genome, name);
    RobotEvaluation& evaluation = robot.evaluation.emplace();
    evaluation.config = archive.config_text();
    evaluation.run = a->path;
    evaluation.generation = g;
    evaluation.id = rec.id[row];
    evaluation.fitness = rec.fitness[row];
    evaluation.status = to_string(static_cast<EvalStatus>(rec.status[row]));
    write_robot_file(robot, a->out, a->force ? Overwrite::replace : Overwrite::refuse);
    if (a->json) {
      nlohmann::ordered_json j;
      j["run"] = a->path;
      j["generation"] = g;
      j["id"] = rec.id[row];
      j["fitness"] = rec.fitness[row];
      j["status"] = evaluation.status;
      j["config_hash"] = hash_hex(text_hash(evaluation.config));
      j["experiment_hash"] = hash_hex(experiment_hash_of_text(evaluation.config));
      j["output"] = a->out;
      std::printf("%s\n", j.dump().c_str());
    } else {
      std::printf("%s: generation %lld, id %lld, fitness %s (%s) -> %s\n", a->path.c_str(),
                  static_cast<long long>(g), static_cast<long long>(rec.id[row]),
                  round_trip(rec.fitness[row]).c_str(), evaluation.status.c_str(), a->out.c_str());
    }
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
