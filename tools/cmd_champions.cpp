// `softevo champions [DIR] [--jobs N] [--integrator I] [--only SUBSTR] [--set k=v] [--json]`
//
// Evaluates every robot file of DIR (default the sample robots, robots/; the thesis champions
// when given their folder) with its task (directed controllers: the five directions of §7.4) and
// prints our fitness next to `reference.fitness` (what the thesis simulator gives), then:
//  - the Spearman rank correlation over all robots with a reference (goal >= 0.8);
//  - over the open-loop champions: the median relative difference |ours - ref| / |ref|
//    (goal <= 10 %) and how many fall below half of their reference (goal: none);
//  - how many champions that the thesis simulator does not kill are killed or score <= 0 here.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tasks/task.hpp"
#include "tools/commands.hpp"
#include "validation/champions.hpp"

namespace softevo::cli {
namespace {

using validation::ChampionRow;

struct ChampionsArgs {
  std::string dir = sample_robots_dir();
  int jobs = 1;
  std::string integrator = "pneuvox";
  std::string only;
  std::vector<std::string> overrides;
  bool json = false;
};

double rel_diff(double ours, double ref) {
  return std::fabs(ours - ref) / std::fabs(ref);
}

int run_champions(const ChampionsArgs& a) {
  std::vector<ChampionRow> rows;
  for (const std::string& f : validation::robot_files(a.dir)) {
    if (!a.only.empty() && f.find(a.only) == std::string::npos) continue;
    rows.push_back(validation::load_champion(f));
  }
  if (rows.empty()) throw std::runtime_error(a.dir + ": no robot files selected");
  std::fprintf(stderr, "evaluating %zu robots on %d thread(s), integrator %s\n", rows.size(),
               a.jobs, a.integrator.c_str());
  validation::evaluate_champions(
      rows, a.overrides, parse_choice<Integrator>(a.integrator, "--integrator"), a.jobs,
      [](const ChampionRow& r) {
        std::fprintf(stderr, "  %-16s ours %12.6f  ref %10.4f  %s  (%.1f s CPU)\n",
                     r.robot.name.c_str(), r.result.fitness, r.ref_fitness,
                     to_string(r.result.status), r.cpu_seconds);
      });

  std::vector<double> ours_all, ref_all, open_diff;
  int below_half = 0, not_walking = 0, walkers = 0;
  for (const ChampionRow& r : rows) {
    if (!r.has_reference) continue;
    ours_all.push_back(r.result.fitness);
    ref_all.push_back(r.ref_fitness);
    if (!r.robot.controller.closed_loop && r.ref_fitness > 0.0) {
      open_diff.push_back(rel_diff(r.result.fitness, r.ref_fitness));
      if (r.result.fitness < 0.5 * r.ref_fitness) ++below_half;
    }
    if (!r.ref_killed && r.ref_fitness > 0.0) {
      ++walkers;
      if (is_killed(r.result.status) || !(r.result.fitness > 0.0)) ++not_walking;
    }
  }
  const double rho = validation::spearman(ours_all, ref_all);
  const double open_median = validation::median(open_diff);

  if (a.json) {
    nlohmann::ordered_json j;
    j["integrator"] = a.integrator;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const ChampionRow& r : rows) {
      nlohmann::ordered_json e;
      e["name"] = r.robot.name;
      e["control"] = r.robot.controller.closed_loop ? "closed" : "open";
      e["directed"] = r.robot.controller.directed;
      e["fitness"] = r.result.fitness;
      e["status"] = to_string(r.result.status);
      if (r.has_reference) {
        e["reference_fitness"] = r.ref_fitness;
        e["reference_killed"] = r.ref_killed;
      }
      nlohmann::ordered_json per = nlohmann::ordered_json::array();
      for (const auto& c : r.result.components) per.push_back(c.fitness);
      e["per_direction"] = per;
      e["cpu_seconds"] = r.cpu_seconds;
      e["reference_cpu_seconds"] = r.ref_cpu_seconds;
      e["steps"] = r.result.steps;
      e["voxels"] = r.result.voxels;
      e["chambers"] = r.result.chambers;
      list.push_back(e);
    }
    j["robots"] = list;
    j["spearman"] = std::isfinite(rho) ? nlohmann::ordered_json(rho) : nlohmann::ordered_json();
    j["open_loop_count"] = open_diff.size();
    j["open_loop_median_relative_difference"] =
        std::isfinite(open_median) ? nlohmann::ordered_json(open_median) : nlohmann::ordered_json();
    j["open_loop_below_half"] = below_half;
    j["reference_walkers"] = walkers;
    j["reference_walkers_not_walking_here"] = not_walking;
    std::printf("%s\n", j.dump(1).c_str());
    return kExitOk;
  }
  std::printf("%-16s %-6s %-8s %3s %20s %11s %8s  %-17s %8s %8s\n", "robot", "loop", "task", "ch",
              "ours", "reference", "rel.diff", "status", "cpu[s]", "ref cpu");
  for (const ChampionRow& r : rows) {
    const double d = r.has_reference && r.ref_fitness != 0.0
                         ? rel_diff(r.result.fitness, r.ref_fitness)
                         : std::nan("");
    std::printf("%-16s %-6s %-8s %3d %20.12f %11.4f %7.1f%%  %-17s %8.1f %8.1f%s\n",
                r.robot.name.c_str(), r.robot.controller.closed_loop ? "closed" : "open",
                to_string(tasks::default_task_for(r.robot.controller.task_inputs())),
                r.result.chambers, r.result.fitness, r.ref_fitness, 100.0 * d,
                to_string(r.result.status), r.cpu_seconds, r.ref_cpu_seconds,
                r.ref_killed ? "  (ref killed)" : "");
  }
  std::printf("\nSpearman rank correlation (%zu robots): %.4f   (goal >= 0.8)\n", ours_all.size(),
              rho);
  std::printf(
      "open loop (%zu robots): median relative difference %.2f%% (goal <= 10%%), "
      "%d below half of the reference (goal 0)\n",
      open_diff.size(), 100.0 * open_median, below_half);
  std::printf("walkers of the reference (%d): %d killed or not moving forward here\n", walkers,
              not_walking);
  return kExitOk;
}

}  // namespace

void register_champions(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "champions", "evaluate robot files with `reference` values (thesis champions) and compare");
  auto a = std::make_shared<ChampionsArgs>();
  cmd->add_option("DIR", a->dir, "directory of robot files")->capture_default_str();
  cmd->add_option("--jobs", a->jobs, "evaluation threads")->check(CLI::Range(1, 64));
  cmd->add_option("--integrator", a->integrator, "physics integrator")
      ->check(CLI::IsMember(choice_names<Integrator>()));
  cmd->add_option("--only", a->only, "only files whose path contains this text");
  cmd->add_option("--set", a->overrides, "override a config key: section.key=value");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->callback([&exit_code, a] { exit_code = run_champions(*a); });
}

}  // namespace softevo::cli
