// `softevo info RUN.h5 [--json]`: summary of a run archive (docs/archive.md): metadata, state,
// per-generation best/mean, the resolved config, and two digests for one-line comparisons:
// fitness_digest (every archived generation, id, status, fitness bits) and content_digest
// (everything deterministic, see io/archive.hpp). It also runs the integrity checks --resume
// requires (master/archive_check.hpp) and exits 1 when one fails. It counts the robots of each
// status (all generations, and the last) and names the champion (best of the last generation)
// with its status: a killed champion is flagged, not passed off as a result.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/printable.hpp"
#include "io/archive.hpp"
#include "io/run_lock.hpp"
#include "master/archive_check.hpp"
#include "master/run_state.hpp"
#include "tasks/task.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {
namespace {

struct Champion {
  std::int64_t generation = 0;
  std::int64_t id = 0;
  double fitness = 0.0;
  std::string status;
  std::optional<double> fitness_before;  // a learning run's: the genome as born
  std::int64_t learn_evaluations = 0;
};

// Controller learning over the whole run (docs/model.md §8.11): bodies that learned (evaluated
// in their generation, not reused), the evaluations they cost, and their fitness gained.
struct LearningTotals {
  std::int64_t bodies = 0;
  std::int64_t evaluations = 0;
  double gain_sum = 0.0;
  double gain_best = 0.0;
  std::int64_t iterations = 0;  // strategy iterations per body (curve points - 1)
  void add(const io::GenerationRecord& r) {
    iterations = r.learning_points - 1;
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (r.reused_from[i] != io::kNotReused) continue;
      ++bodies;
      evaluations += r.learn_evaluations[i];
      const double gain = r.fitness[i] - r.fitness_before[i];
      gain_sum += gain;
      gain_best = std::max(gain_best, gain);
    }
  }
};

// Every status in EvalStatus order, with its count (0 included: "no killed robot" is news too).
std::vector<std::pair<std::string, std::int64_t>> status_rows(
    const std::map<std::string, std::int64_t>& counts) {
  std::vector<std::pair<std::string, std::int64_t>> rows;
  for (int code = 0; code <= static_cast<int>(EvalStatus::invalid_body); ++code) {
    const std::string name = to_string(static_cast<EvalStatus>(code));
    const auto it = counts.find(name);
    rows.emplace_back(name, it == counts.end() ? 0 : it->second);
  }
  for (const auto& [name, n] : counts)  // a status code this build does not know
    if (name == "unknown") rows.emplace_back(name, n);
  return rows;
}

nlohmann::ordered_json status_json(const std::map<std::string, std::int64_t>& counts) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [name, n] : status_rows(counts)) j[name] = n;
  return j;
}

std::string status_text(const std::map<std::string, std::int64_t>& counts) {
  std::string text;
  for (const auto& [name, n] : status_rows(counts))
    text += (text.empty() ? "" : ", ") + name + " " + std::to_string(n);
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
    const io::Archive archive(*path);
    const io::RunInfo info = archive.info();
    const master::ArchiveCheck check = master::check_archive(archive);
    // "running" is what a live run and a dead one both leave; the run lock tells them apart.
    const std::optional<std::string> holder = io::lock_holder(*path);
    std::optional<std::int64_t> generations;  // the run's target, if its config parses
    std::string fitness_unit = "task units";  // the table's unit, if its config parses
    try {
      const Config config = parse_config(archive.config_text(), *path + ":/config");
      generations = config.run.generations;
      fitness_unit = tasks::make_task(config)->fitness_unit();
    } catch (const std::exception&) {
    }
    const std::optional<std::string> note = master::previous_run_note(info, holder, generations);
    // A damaged archive is still summarised as far as it can be read; the checks say what
    // is wrong.
    const auto or_unreadable = [](auto&& read) -> std::string {
      try {
        return read();
      } catch (const io::ArchiveError&) {
        return "(unreadable)";
      }
    };
    std::vector<io::StatsRow> stats;
    try {
      stats = archive.stats();
    } catch (const io::ArchiveError&) {
    }
    const std::string fitness =
        or_unreadable([&] { return hash_hex(io::fitness_digest(archive)); });
    const std::string content =
        or_unreadable([&] { return hash_hex(io::content_digest(archive)); });
    std::optional<io::Checkpoint> checkpoint;
    try {
      checkpoint = archive.checkpoint();
    } catch (const io::ArchiveError&) {
    }
    const std::string config_text = or_unreadable([&] { return archive.config_text(); });
    // Robots per status, over every generation and in the last; the last generation's best.
    std::map<std::string, std::int64_t> all_statuses, last_statuses;
    std::optional<Champion> champion;
    std::optional<LearningTotals> learning;
    try {
      const std::vector<std::int64_t> gens = archive.generations();
      for (const std::int64_t g : gens) {
        const io::GenerationRecord r = archive.generation(g);
        if (r.has_learning()) {
          if (!learning) learning.emplace();
          learning->add(r);
        }
        for (const std::uint8_t code : r.status) {
          const std::string name = to_string(static_cast<EvalStatus>(code));
          ++all_statuses[name];
          if (g == gens.back()) ++last_statuses[name];
        }
        if (g == gens.back() && r.size() > 0) {
          std::size_t best = 0;
          for (std::size_t i = 1; i < r.size(); ++i)
            if (r.fitness[i] > r.fitness[best]) best = i;
          champion.emplace();
          champion->generation = g;
          champion->id = r.id[best];
          champion->fitness = r.fitness[best];
          champion->status = to_string(static_cast<EvalStatus>(r.status[best]));
          if (r.has_learning()) {
            champion->fitness_before = r.fitness_before[best];
            champion->learn_evaluations = r.learn_evaluations[best];
          }
        }
      }
    } catch (const io::ArchiveError&) {
    }
    if (*json) {
      nlohmann::ordered_json j;
      j["path"] = *path;
      j["format"] = info.format;
      j["version"] = info.version;
      j["git_commit"] = info.git_commit;
      j["physics_revision"] = info.physics_revision;
      j["seed"] = info.seed;
      j["ranks"] = info.ranks;
      j["host"] = info.host;
      j["start_time"] = info.start_time;
      j["end_time"] = info.end_time;
      j["config_hash"] = info.config_hash;
      j["experiment"] = info.experiment;
      j["state"] = info.state;
      j["stop_reason"] = info.stop_reason.empty() ? nlohmann::ordered_json()
                                                  : nlohmann::ordered_json(info.stop_reason);
      j["lock_holder"] = holder ? nlohmann::ordered_json(*holder) : nlohmann::ordered_json();
      j["state_note"] = note ? nlohmann::ordered_json(*note) : nlohmann::ordered_json();
      j["generations_done"] = info.generations_done;
      j["checkpoint_generation"] =
          checkpoint ? nlohmann::ordered_json(checkpoint->generation) : nlohmann::ordered_json();
      j["experiment_hash"] = info.experiment_hash;
      j["fitness_digest"] = fitness;
      j["content_digest"] = content;
      j["status_counts"] = status_json(all_statuses);
      j["last_generation_status_counts"] = status_json(last_statuses);
      j["champion"] = champion ? nlohmann::ordered_json{{"generation", champion->generation},
                                                        {"id", champion->id},
                                                        {"fitness", champion->fitness},
                                                        {"status", champion->status}}
                               : nlohmann::ordered_json();
      if (champion && champion->fitness_before) {
        j["champion"]["fitness_before"] = *champion->fitness_before;
        j["champion"]["learn_evaluations"] = champion->learn_evaluations;
      }
      j["learning"] =
          learning
              ? nlohmann::ordered_json{{"bodies_learned", learning->bodies},
                                       {"evaluations", learning->evaluations},
                                       {"iterations", learning->iterations},
                                       {"mean_gain", learning->bodies > 0
                                                         ? learning->gain_sum /
                                                               static_cast<double>(learning->bodies)
                                                         : 0.0},
                                       {"best_gain", learning->gain_best}}
              : nlohmann::ordered_json();
      auto& gens = j["generations"] = nlohmann::ordered_json::array();
      for (const auto& s : stats)
        gens.push_back({{"generation", static_cast<std::int64_t>(s.generation)},
                        {"best", s.best},
                        {"mean", s.mean},
                        {"sd", s.sd},
                        {"species_count", static_cast<std::int64_t>(s.species_count)},
                        {"evaluations_per_second", s.evaluations_per_second}});
      j["config"] = config_text;
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
      std::printf("state            %s, %lld generations done%s\n", shown(info.state).c_str(),
                  static_cast<long long>(info.generations_done),
                  holder ? (" (written now by " + shown(*holder) + ")").c_str() : "");
      if (note) std::printf("                 %s\n", note->c_str());
      if (!info.stop_reason.empty())
        std::printf("stopped          %s\n", shown(info.stop_reason).c_str());
      std::printf("written by       softevo %s (commit %s), %d ranks on %s\n",
                  shown(info.version).c_str(), shown(info.git_commit).c_str(), info.ranks,
                  shown(info.host).c_str());
      std::printf("physics revision %d\n", info.physics_revision);
      std::printf("time             %s .. %s\n", shown(info.start_time).c_str(),
                  info.end_time.empty() ? "(running)" : shown(info.end_time).c_str());
      std::printf("robots           %s (all generations)\n", status_text(all_statuses).c_str());
      std::printf("                 %s (last generation)\n", status_text(last_statuses).c_str());
      if (champion)
        std::printf("champion         generation %lld id %lld, fitness %.6g %s, status %s%s\n",
                    static_cast<long long>(champion->generation),
                    static_cast<long long>(champion->id), champion->fitness, fitness_unit.c_str(),
                    champion->status.c_str(),
                    champion->status == "ok" ? "" : "  <- NOT ok: its fitness is 0 by rule");
      if (champion && champion->fitness_before)
        std::printf("                 learned from %.6g in %lld evaluations\n",
                    *champion->fitness_before, static_cast<long long>(champion->learn_evaluations));
      if (learning)
        std::printf(
            "learning         %lld bodies x %lld iterations, %lld evaluations, gain mean "
            "%+.6g best %+.6g\n",
            static_cast<long long>(learning->bodies), static_cast<long long>(learning->iterations),
            static_cast<long long>(learning->evaluations),
            learning->bodies > 0 ? learning->gain_sum / static_cast<double>(learning->bodies) : 0.0,
            learning->gain_best);
      std::printf("fitness_digest   %s\n", fitness.c_str());
      std::printf("content_digest   %s\n", content.c_str());
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
      const std::string in_unit = " [" + fitness_unit + "]";
      std::printf("\n%10s %14s %14s %14s %8s %10s\n", "generation", ("best" + in_unit).c_str(),
                  ("mean" + in_unit).c_str(), ("sd" + in_unit).c_str(), "species", "eval/s");
      for (const auto& s : stats)
        std::printf("%10lld %14.6g %14.6g %14.6g %8lld %10.3g\n",
                    static_cast<long long>(s.generation), s.best, s.mean, s.sd,
                    static_cast<long long>(s.species_count), s.evaluations_per_second);
      if (*verbose)
        std::printf("\n# resolved config\n%s", printable(config_text, Newlines::keep).c_str());
      else
        std::printf("\n(-v prints the resolved config, --json everything)\n");
    }
    exit_code = check.ok() ? kExitOk : kExitMismatch;
  });
}

}  // namespace softevo::cli
