// `softevo bench eval [DIR] [--jobs N] [--integrator I] [--only SUBSTR] [--runs N] [--set K=V]
//  [--json]`
//
// Speed of one 10 s gait evaluation of the thesis gait champions (robot files of DIR whose
// controller is not directed; default the sample robots, robots/), compared with the thesis
// simulator's CPU seconds recorded in each file (`reference.cpu_seconds`, median 33 s). Reports
// per robot our thread CPU seconds, microseconds per voxel-step and evaluation status (a killed
// robot ran fewer steps, so its time is not comparable), and the median speed-up
// (goal >= 5x, one core, pneuvox integrator). CPU time is the figure to compare: wall time
// depends on what else the machine runs. With --runs N every robot is evaluated N times and its
// fastest run is kept (other tenants of a shared machine only ever slow a run down); the runs
// must give bit-identical fitness, else the benchmark stops with an error. --set changes the
// config of every evaluation (e.g. --set terrain.kind=heightfield: the cost of rough ground).
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tasks/task.hpp"
#include "tools/bench_common.hpp"
#include "tools/commands.hpp"
#include "validation/champions.hpp"

namespace softevo::cli {
namespace {

using validation::ChampionRow;

struct BenchEvalArgs {
  std::string dir = sample_robots_dir();
  int jobs = 1;
  std::string integrator = "pneuvox";
  std::string only;
  int runs = 1;
  std::vector<std::string> overrides;  // "section.key=value" for every evaluation
  bool json = false;
};

int run_bench_eval(const BenchEvalArgs& a) {
  std::vector<ChampionRow> rows;
  for (const std::string& f : validation::robot_files(a.dir)) {
    if (!a.only.empty() && f.find(a.only) == std::string::npos) continue;
    ChampionRow row = validation::load_champion(f);
    // The gait robots: those whose controller fits the gait task.
    if (tasks::default_task_for(row.robot.controller.task_inputs()) == TaskKind::gait)
      rows.push_back(std::move(row));
  }
  if (rows.empty()) throw std::runtime_error(a.dir + ": no gait robot files selected");
  std::fprintf(stderr,
               "benchmarking %zu gait evaluations on %d thread(s), integrator %s, best of %d "
               "run(s)\n",
               rows.size(), a.jobs, a.integrator.c_str(), a.runs);
  const std::vector<ChampionRow> unevaluated = rows;
  for (int run = 1; run <= a.runs; ++run) {
    std::vector<ChampionRow> again = unevaluated;
    validation::evaluate_champions(again, a.overrides, a.integrator, a.jobs,
                                   [&](const ChampionRow& r) {
                                     std::fprintf(stderr, "  run %d  %-16s %.2f s CPU\n", run,
                                                  r.robot.name.c_str(), r.cpu_seconds);
                                   });
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (run > 1 && !same_bits(again[i].result.fitness, rows[i].result.fitness))
        throw std::runtime_error(rows[i].file + ": run " + std::to_string(run) +
                                 " gave another fitness than run 1 (the evaluation is not "
                                 "deterministic)");
      if (run == 1 || again[i].cpu_seconds < rows[i].cpu_seconds) rows[i] = std::move(again[i]);
    }
  }
  std::vector<double> ours, ref, speedup, us_per_voxel_step;
  for (const ChampionRow& r : rows) {
    ours.push_back(r.cpu_seconds);
    const double vs = static_cast<double>(r.result.voxels) * static_cast<double>(r.result.steps);
    us_per_voxel_step.push_back(vs > 0 ? 1e6 * r.cpu_seconds / vs : 0.0);
    if (r.ref_cpu_seconds > 0.0) {
      ref.push_back(r.ref_cpu_seconds);
      speedup.push_back(r.ref_cpu_seconds / r.cpu_seconds);
    }
  }
  const double med_ours = validation::median(ours), med_ref = validation::median(ref),
               med_speedup = validation::median(speedup);
  if (a.json) {
    nlohmann::ordered_json j;
    j["integrator"] = a.integrator;
    j["robots"] = rows.size();
    j["runs"] = a.runs;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < rows.size(); ++i)
      list.push_back({{"name", rows[i].robot.name},
                      {"status", to_string(rows[i].result.status)},
                      {"fitness", rows[i].result.fitness},
                      {"cpu_seconds", rows[i].cpu_seconds},
                      {"wall_seconds", rows[i].result.wall_seconds},
                      {"reference_cpu_seconds", rows[i].ref_cpu_seconds},
                      {"voxels", rows[i].result.voxels},
                      {"steps", rows[i].result.steps},
                      {"us_per_voxel_step", us_per_voxel_step[i]}});
    j["per_robot"] = list;
    j["median_cpu_seconds"] = med_ours;
    j["median_reference_cpu_seconds"] = med_ref;
    j["median_speedup"] = med_speedup;
    j["median_us_per_voxel_step"] = validation::median(us_per_voxel_step);
    std::printf("%s\n", j.dump(1).c_str());
    return kExitOk;
  }
  if (a.runs > 1) std::printf("fastest of %d runs per robot\n", a.runs);
  std::printf("%-16s %6s %7s %9s %9s %8s %8s %8s  %s\n", "robot", "voxels", "steps", "cpu[s]",
              "wall[s]", "ref[s]", "speedup", "us/v-st", "status");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ChampionRow& r = rows[i];
    std::printf("%-16s %6d %7lld %9.2f %9.2f %8.2f %7.2fx %8.3f  %s\n", r.robot.name.c_str(),
                r.result.voxels, static_cast<long long>(r.result.steps), r.cpu_seconds,
                r.result.wall_seconds, r.ref_cpu_seconds,
                r.ref_cpu_seconds > 0 ? r.ref_cpu_seconds / r.cpu_seconds : 0.0,
                us_per_voxel_step[i], to_string(r.result.status));
  }
  std::printf(
      "\nmedian CPU seconds: ours %.2f, thesis simulator %.2f; median speed-up %.2fx "
      "(goal >= 5x); median %.3f us per voxel-step (thesis 0.65)\n",
      med_ours, med_ref, med_speedup, validation::median(us_per_voxel_step));
  return kExitOk;
}

}  // namespace

void register_bench_eval(CLI::App& app, int& exit_code) {
  CLI::App* bench = bench_group(app);
  auto* cmd = bench->add_subcommand(
      "eval", "CPU time of 10 s gait evaluations of the thesis gait champions vs the thesis");
  auto a = std::make_shared<BenchEvalArgs>();
  cmd->add_option("DIR", a->dir, "directory of robot files")->capture_default_str();
  cmd->add_option("--jobs", a->jobs, "evaluation threads (1 = one core)")->check(CLI::Range(1, 64));
  cmd->add_option("--integrator", a->integrator, "physics integrator")
      ->check(CLI::IsMember({"pneuvox", "symplectic"}));
  cmd->add_option("--only", a->only, "only files whose path contains this text");
  cmd->add_option("--runs", a->runs,
                  "evaluations per robot; the fastest is kept (all must give the same fitness)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--set", a->overrides, "override a config key: section.key=value");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->callback([&exit_code, a] { exit_code = run_bench_eval(*a); });
}

}  // namespace softevo::cli
