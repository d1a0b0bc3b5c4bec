// `softevo repair RUN.h5 -o FIXED.h5`: copies the consistent generations of a damaged run
// archive into a NEW archive that --resume continues (docs/archive.md "Integrity checks").
// RUN.h5 is only read. The kept generations are those before the first one that fails a
// check (master/archive_check.hpp); their checkpoint is rebuilt by replaying the archived
// results through the population from the run's seed (reproduction is deterministic), and
// each replayed generation's ids must equal the archived ones.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/printable.hpp"
#include "common/safe_write.hpp"
#include "evo/search_strategy.hpp"
#include "io/archive.hpp"
#include "master/archive_check.hpp"
#include "tasks/task.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {
namespace {

std::vector<evo::Evaluation> evaluations_of(const io::GenerationRecord& r) {
  std::vector<evo::Evaluation> e;
  e.reserve(r.size());
  for (std::size_t i = 0; i < r.size(); ++i)
    e.push_back(evo::Evaluation{r.id[i], r.fitness[i], r.status[i] != 0});
  return e;
}

std::vector<std::int64_t> sorted_member_ids(const evo::SearchStrategy& population) {
  std::vector<std::int64_t> ids;
  for (const evo::Individual& m : population.members()) ids.push_back(m.id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

// Writes generations [0, keep) of `in` to `out_path` (a new file); returns how many it kept
// (fewer when the replay disagrees with the archive).
std::int64_t write_repaired(const io::Archive& in, std::int64_t keep, const std::string& out_path) {
  const std::string config_text = in.config_text();
  const Config config = parse_config(config_text, in.path() + ":/config");
  io::RunInfo info = in.info();
  info.generations_done = 0;
  info.state = io::RunState::interrupted;
  // The run's search strategy (NEAT's population, the MAP-Elites map, AFPO), replayed.
  const std::unique_ptr<evo::SearchStrategy> strategy =
      evo::make_strategy(config, tasks::make_task(config)->controller_inputs(),
                         static_cast<std::uint64_t>(config.run.seed));
  evo::SearchStrategy& population = *strategy;
  AtomicOutput output(out_path, Overwrite::refuse);
  // Written as a run writes (segments beside the temporary), then packed into the one file
  // that is renamed into place.
  struct DiscardUnlessPacked {
    const std::string& temp;
    bool packed = false;
    ~DiscardUnlessPacked() {
      if (!packed) io::remove_archive(temp);
    }
  } discard{output.temp_path()};
  io::create_archive(output.temp_path(), info, config_text);
  std::int64_t kept = 0;
  for (std::int64_t g = 0; g < keep; ++g) {
    const io::GenerationRecord r = in.generation(g);
    if (population.generation() != g || sorted_member_ids(population) != r.id) {
      std::fprintf(stderr,
                   "softevo repair: generation %lld: the replayed population does not match the "
                   "archived ids; keeping generations 0..%lld\n",
                   static_cast<long long>(g), static_cast<long long>(g) - 1);
      break;
    }
    population.tell(evaluations_of(r));
    const io::StatsRow stats{
        static_cast<double>(g),
        r.best,
        r.mean,
        r.sd,
        static_cast<double>(r.species_count),
        r.eval_wall_seconds > 0 ? static_cast<double>(r.evaluations) / r.eval_wall_seconds : 0.0};
    info.generations_done = g + 1;
    io::append_generation(output.temp_path(), info, r, stats,
                          io::Checkpoint{population.generation(), population.serialize()});
    kept = g + 1;
  }
  io::finish_archive(output.temp_path(), info);
  discard.packed = true;
  output.commit();
  return kept;
}

}  // namespace

void register_repair(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "repair", "copy the consistent generations of a damaged run archive into a new archive");
  auto path = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  cmd->add_option("RUN", *path, "damaged run archive (.h5); only read")->required();
  cmd->add_option("-o,--output,--out", *out, "new archive to write (must not exist)")->required();
  cmd->callback([&exit_code, path, out] {
    const io::Archive archive(*path);
    const master::ArchiveCheck check = master::check_archive(archive);
    for (const master::ArchiveProblem& p : check.problems)
      if (p.generation < 0 && p.check == "config")
        throw io::ArchiveError(*path + ": cannot repair: " + p.message);
    if (check.ok()) {
      std::printf("%s passes every check; nothing to repair (nothing written)\n", path->c_str());
      exit_code = kExitOk;
      return;
    }
    std::fprintf(stderr, "%s", printable(check.describe(*path), Newlines::keep).c_str());
    const std::int64_t kept = write_repaired(archive, check.consistent_generations, *out);
    std::printf(
        "%s: wrote generations 0..%lld of %s (state interrupted); continue it with "
        "softevo-mpi --resume --out %s\n",
        out->c_str(), static_cast<long long>(kept) - 1, path->c_str(), out->c_str());
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
