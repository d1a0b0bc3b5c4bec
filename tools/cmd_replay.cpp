// `softevo replay`: evaluate archived individuals again (validation/replay.hpp) and, with
// --verify, check that the result is bit-identical to what the run archived. A difference in
// fitness bits, status or any archived fitness component is a mismatch (exit code 1).
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "common/eval_types.hpp"
#include "common/round_trip.hpp"
#include "tools/commands.hpp"
#include "tools/elite_cell.hpp"
#include "validation/replay.hpp"

namespace softevo::cli {
namespace {

struct ReplayArgs {
  std::string archive;
  std::optional<std::int64_t> generation;
  std::optional<std::int64_t> id;
  bool best = false;
  bool verify = false;
  bool all = false;
  bool json = false;
};

int run_replay(const ReplayArgs& args) {
  const validation::ReplaySelection selection =
      validation::select_for_replay(args.archive, args.generation, args.id, args.all, args.verify);
  if (selection.revision_note)
    std::fprintf(stderr, "softevo: note: %s\n", selection.revision_note->c_str());
  const std::unique_ptr<tasks::Task> task = tasks::make_task(selection.individuals.front().config);
  int identical = 0, mismatched = 0, unverifiable = 0;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const motion::ArchivedIndividual& ind : selection.individuals) {
    const validation::ReplayResult r =
        validation::replay(ind, *task, selection.config_hash, args.verify);
    const char* verdict = !args.verify         ? ""
                          : !r.verifiable      ? "SKIPPED"
                          : r.mismatch.empty() ? "IDENTICAL"
                                               : "MISMATCH";
    if (args.verify && !r.verifiable) ++unverifiable;
    if (args.verify && r.verifiable) ++(r.mismatch.empty() ? identical : mismatched);
    if (args.json) {
      nlohmann::ordered_json row;
      row["generation"] = ind.generation;
      row["id"] = ind.id;
      row["fitness"] = r.outcome.fitness;
      row["status"] = to_string(r.outcome.status);
      row["archived_fitness"] = ind.fitness;
      row["archived_status"] = to_string(static_cast<EvalStatus>(ind.status));
      if (args.verify) {
        row["verdict"] = verdict;
        row["mismatch"] = r.mismatch;
      }
      rows.push_back(row);
      continue;
    }
    std::printf("generation %lld id %lld: fitness %s status %s (archived %s %s)",
                static_cast<long long>(ind.generation), static_cast<long long>(ind.id),
                round_trip(r.outcome.fitness).c_str(), to_string(r.outcome.status),
                round_trip(ind.fitness).c_str(), to_string(static_cast<EvalStatus>(ind.status)));
    if (!args.verify) {
      std::printf("\n");
    } else if (!r.verifiable) {
      std::printf("  SKIPPED (archived timeout is wall-clock dependent)\n");
    } else if (r.mismatch.empty()) {
      std::printf("  IDENTICAL\n");
    } else {
      std::printf("  MISMATCH: %s\n", r.mismatch.c_str());
    }
  }
  if (args.json) {
    nlohmann::ordered_json j;
    j["run"] = args.archive;
    j["generation"] = selection.individuals.front().generation;
    j["individuals"] = rows;
    if (args.verify) {
      j["identical"] = identical;
      j["mismatched"] = mismatched;
      j["skipped"] = unverifiable;
    }
    std::printf("%s\n", j.dump().c_str());
  } else if (args.verify) {
    std::printf("verify %s generation %lld: %d identical, %d mismatched, %d skipped of %zu\n",
                args.archive.c_str(),
                static_cast<long long>(selection.individuals.front().generation), identical,
                mismatched, unverifiable, selection.individuals.size());
  }
  if (!args.verify) return kExitOk;
  return mismatched == 0 ? kExitOk : kExitMismatch;
}

}  // namespace

void register_replay(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "replay",
      "re-simulate archived individuals from their genome and the archived config; --verify "
      "checks bit-identity with the archived fitness (exit 1 on mismatch)");
  auto args = std::make_shared<ReplayArgs>();
  cmd->add_option("RUN", args->archive, "run archive (softevo.run/1 HDF5)")->required();
  const auto [id_opt, best_opt] =
      add_individual_options(*cmd, args->generation, args->id, args->best, nullptr, "");
  cmd->add_flag("--verify", args->verify,
                "compare fitness, status and components bit for bit with the archive");
  cmd->add_flag("--all", args->all, "every individual of the generation (audit)")
      ->excludes(id_opt)
      ->excludes(best_opt);
  cmd->add_flag("--json", args->json, "print one JSON object (one entry per individual)");
  cmd->callback([&exit_code, args] { exit_code = run_replay(*args); });
}

}  // namespace softevo::cli
