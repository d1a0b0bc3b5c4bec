// `softevo info RUN.h5 [--json]`: prints the summary of a run archive (master/run_summary.hpp):
// metadata, state, per-generation best/mean, the resolved config, and two digests for one-line
// comparisons: fitness_digest (every archived generation, id, status, fitness bits) and
// content_digest (everything deterministic, see io/archive.hpp). Exits 1 when an integrity check
// --resume requires fails. A champion that is not ok is flagged, not passed off as a result.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/printable.hpp"
#include "master/run_summary.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {
namespace {

nlohmann::ordered_json status_json(const std::vector<master::StatusCount>& counts) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const master::StatusCount& c : counts) j[c.status] = c.count;
  return j;
}

std::string status_text(const std::vector<master::StatusCount>& counts) {
  std::string text;
  for (const master::StatusCount& c : counts)
    text += (text.empty() ? "" : ", ") + c.status + " " + std::to_string(c.count);
  return text;
}

}  // namespace

void register_info(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("info", "summarise a run archive (softevo.run/1)");
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto verbose = std::make_shared<bool>(false);
  cmd->add_option("RUN", *path, "run archive (.h5)")->required();
  cmd->add_flag("--json", *json, "machine-readable output");
  cmd->add_flag("-v,--verbose", *verbose, "print the resolved config too");
  cmd->callback([&exit_code, path, json, verbose] {
    const master::RunSummary summary = master::summarize_run(*path);
    const io::RunInfo& info = summary.info;
    const master::ArchiveCheck& check = summary.check;
    const std::optional<std::string>& holder = summary.lock_holder;
    const std::optional<std::string>& note = summary.state_note;
    const std::optional<master::Champion>& champion = summary.champion;
    const std::optional<master::LearningTotals>& learning = summary.learning;
    if (*json) {
      nlohmann::ordered_json j;
      j["path"] = *path;
      j["format"] = info.format;
      j["version"] = info.version;
      j["git_commit"] = info.git_commit;
      j["physics_revision"] = info.physics_revision;
      j["seed"] = info.seed;
      j["ranks"] = info.ranks;
      j["program"] = info.program;
      j["host"] = info.host;
      j["start_time"] = info.start_time;
      j["end_time"] = info.end_time;
      j["config_hash"] = info.config_hash;
      j["experiment"] = info.experiment;
      j["state"] = to_string(info.state);
      j["stop_reason"] = info.stop_reason.empty() ? nlohmann::ordered_json()
                                                  : nlohmann::ordered_json(info.stop_reason);
      j["lock_holder"] = holder ? nlohmann::ordered_json(*holder) : nlohmann::ordered_json();
      j["state_note"] = note ? nlohmann::ordered_json(*note) : nlohmann::ordered_json();
      j["generations_done"] = info.generations_done;
      j["checkpoint_generation"] = summary.checkpoint_generation
                                       ? nlohmann::ordered_json(*summary.checkpoint_generation)
                                       : nlohmann::ordered_json();
      j["experiment_hash"] = info.experiment_hash;
      j["strategy"] = summary.strategy;
      j["fitness_digest"] = summary.fitness_digest;
      j["content_digest"] = summary.content_digest;
      j["status_counts"] = status_json(summary.statuses);
      j["last_generation_status_counts"] = status_json(summary.last_generation_statuses);
      j["champion"] = champion ? nlohmann::ordered_json{{"generation", champion->generation},
                                                        {"id", champion->id},
                                                        {"fitness", champion->fitness},
                                                        {"status", champion->status}}
                               : nlohmann::ordered_json();
      if (champion && champion->fitness_before) {
        j["champion"]["fitness_before"] = *champion->fitness_before;
        j["champion"]["learn_evaluations"] = champion->learn_evaluations;
      }
      j["learning"] = learning ? nlohmann::ordered_json{{"bodies_learned", learning->bodies},
                                                        {"evaluations", learning->evaluations},
                                                        {"iterations", learning->iterations},
                                                        {"mean_gain", learning->mean_gain()},
                                                        {"gain_unit", summary.fitness_unit},
                                                        {"best_gain", learning->gain_best}}
                               : nlohmann::ordered_json();
      auto& gens = j["generations"] = nlohmann::ordered_json::array();
      for (const auto& s : summary.stats)
        gens.push_back({{"generation", static_cast<std::int64_t>(s.generation)},
                        {"best", s.best},
                        {"mean", s.mean},
                        {"sd", s.sd},
                        {"species_count", static_cast<std::int64_t>(s.species_count)},
                        {"evaluations_per_second", s.evaluations_per_second}});
      // A strategy other than NEAT: its metrics per generation (docs/model.md §8.12).
      for (const master::StrategyMetrics& m : summary.strategy_metrics)
        for (auto& g : gens)
          if (g["generation"] == m.generation)
            for (const auto& [name, value] : m.metrics) g[name] = value;
      j["config"] = summary.config_text;
      auto& integrity = j["integrity"];
      integrity["ok"] = check.ok();
      integrity["generations_checked"] = check.generations_checked;
      integrity["generations_with_digest"] = check.generations_with_digest;
      integrity["consistent_generations"] = check.consistent_generations;
      auto& problems = integrity["problems"] = nlohmann::ordered_json::array();
      for (const master::ArchiveProblem& p : check.problems)
        problems.push_back(
            {{"generation", p.generation}, {"check", p.check}, {"message", p.message}});
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      // Archive strings are shown escaped: a file may carry terminal control sequences.
      const auto shown = [](const std::string& text) { return printable(text); };
      std::printf("archive          %s (%s)\n", shown(*path).c_str(), shown(info.format).c_str());
      std::printf("experiment       %s (hash %s), seed %lld, config hash %s\n",
                  shown(info.experiment).c_str(), shown(info.experiment_hash).c_str(),
                  static_cast<long long>(info.seed), shown(info.config_hash).c_str());
      std::printf("search strategy  %s\n", summary.strategy.c_str());
      std::printf("state            %s, %lld generations done%s\n", to_string(info.state),
                  static_cast<long long>(info.generations_done),
                  holder ? (" (written now by " + shown(*holder) + ")").c_str() : "");
      if (note) std::printf("                 %s\n", note->c_str());
      if (!info.stop_reason.empty())
        std::printf("stopped          %s\n", shown(info.stop_reason).c_str());
      // softevo evolve and softevo.evolve record ranks = worker threads + 1 (the master), as
      // softevo-mpi at that many ranks would have written the same archive.
      const bool threads = info.program != "softevo-mpi";
      const int workers = threads ? info.ranks - 1 : info.ranks;
      std::printf("written by       %s %s (commit %s), %d %s on %s\n", shown(info.program).c_str(),
                  shown(info.version).c_str(), shown(info.git_commit).c_str(), workers,
                  threads ? (workers == 1 ? "worker thread" : "worker threads") : "ranks",
                  shown(info.host).c_str());
      std::printf("physics revision %d\n", info.physics_revision);
      std::printf("time             %s .. %s\n", shown(info.start_time).c_str(),
                  info.end_time.empty() ? "(running)" : shown(info.end_time).c_str());
      std::printf("robots           %s (all generations)\n", status_text(summary.statuses).c_str());
      std::printf("                 %s (last generation)\n",
                  status_text(summary.last_generation_statuses).c_str());
      if (champion)
        std::printf("champion         generation %lld id %lld, fitness %.6g %s, status %s%s\n",
                    static_cast<long long>(champion->generation),
                    static_cast<long long>(champion->id), champion->fitness,
                    summary.fitness_unit.c_str(), champion->status.c_str(),
                    champion->status == "ok" ? "" : "  <- NOT ok: its fitness is 0 by rule");
      if (champion && champion->fitness_before)
        std::printf("                 learned from %.6g in %lld evaluations\n",
                    *champion->fitness_before, static_cast<long long>(champion->learn_evaluations));
      if (learning)
        std::printf(
            "learning         %lld bodies x %lld iterations, %lld evaluations, gain mean "
            "%+.6g %s best %+.6g %s\n",
            static_cast<long long>(learning->bodies), static_cast<long long>(learning->iterations),
            static_cast<long long>(learning->evaluations), learning->mean_gain(),
            summary.fitness_unit.c_str(), learning->gain_best, summary.fitness_unit.c_str());
      std::printf("fitness_digest   %s\n", summary.fitness_digest.c_str());
      std::printf("content_digest   %s\n", summary.content_digest.c_str());
      if (check.ok())
        std::printf("integrity        ok (%lld generations checked, %lld with a stored digest%s)\n",
                    static_cast<long long>(check.generations_checked),
                    static_cast<long long>(check.generations_with_digest),
                    check.generations_with_digest < check.generations_checked
                        ? "; the others predate digests and pass the other checks"
                        : "");
      else
        std::printf("integrity        FAILED: %zu problem(s); generations 0..%lld consistent\n%s",
                    check.problems.size(), static_cast<long long>(check.consistent_generations) - 1,
                    printable(check.describe(*path), Newlines::keep).c_str());
      // The unit in every header that has one (fitness in the task's unit, cm or rad).
      const std::string in_unit = " [" + summary.fitness_unit + "]";
      std::printf("\n%10s %14s %14s %14s %8s %10s\n", "generation", ("best" + in_unit).c_str(),
                  ("mean" + in_unit).c_str(), ("sd" + in_unit).c_str(), "species", "eval/s");
      for (const auto& s : summary.stats)
        std::printf("%10lld %14.6g %14.6g %14.6g %8lld %10.3g\n",
                    static_cast<long long>(s.generation), s.best, s.mean, s.sd,
                    static_cast<long long>(s.species_count), s.evaluations_per_second);
      if (!summary.strategy_metrics.empty()) {
        std::printf("\n%10s", "generation");
        for (const auto& [name, value] : summary.strategy_metrics.front().metrics)
          std::printf(" %14s", name.c_str());
        std::printf("\n");
        for (const master::StrategyMetrics& m : summary.strategy_metrics) {
          std::printf("%10lld", static_cast<long long>(m.generation));
          for (const auto& [name, value] : m.metrics) std::printf(" %14.6g", value);
          std::printf("\n");
        }
      }
      if (*verbose)
        std::printf("\n# resolved config\n%s",
                    printable(summary.config_text, Newlines::keep).c_str());
      else
        std::printf("\n(-v prints the resolved config, --json everything)\n");
    }
    exit_code = check.ok() ? kExitOk : kExitMismatch;
  });
}

}  // namespace softevo::cli
