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
//
// `--baseline BIN` compares two builds instead (A/B on one machine): every robot is evaluated as
// a separate `softevo eval ROBOT --json` process by BIN (another build's softevo) and by this
// build, in turn (BIN first on odd runs, this build first on even runs, so that a drift of the
// machine's speed hits both), --runs times each; the fastest CPU time of each build is kept, and
// every run of both builds must give the same fitness bits. --with SUBSTR adds robot files of
// any task (e.g. --with dir-open-09: a directed champion, all its directions). Printed: per
// robot both CPU times and their ratio (baseline / this), the median and the worst robot.
// --csv FILE appends one row per robot (date, CPU, SIMD width, both commits, times): the
// machine's benchmark record (benchmarks/results/).
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/version.hpp"
#include "physics/model.hpp"
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
  std::string baseline;           // another build's softevo: A/B mode
  std::vector<std::string> with;  // robot files of any task, by path substring
  std::string csv;                // A/B rows appended here
};

// ---- A/B of two builds ----------------------------------------------------------------------

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// stdout of a shell command and its exit status (-1: not run or killed).
std::pair<std::string, int> capture(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return {out, -1};
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  const int status = ::pclose(pipe);
  return {out, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

struct ProcessEval {
  double fitness = 0.0;
  double cpu_seconds = 0.0;  // the evaluation's process CPU time, as `softevo eval` reports it
  std::string status, simd;
  int voxels = 0;
  long long steps = 0;
};

// One `EXE eval FILE --json` (integrator and overrides as given) in its own process.
ProcessEval eval_process(const std::string& exe, const std::string& file, const BenchEvalArgs& a) {
  std::string cmd = shell_quote(exe) + " eval " + shell_quote(file) + " --json --integrator " +
                    shell_quote(a.integrator);
  for (const std::string& o : a.overrides) cmd += " --set " + shell_quote(o);
  const auto [out, code] = capture(cmd + " 2>/dev/null");
  const std::size_t brace = out.find('{');
  if (code != 0 || brace == std::string::npos)
    throw std::runtime_error(exe + " eval " + file + " failed (exit " + std::to_string(code) +
                             "): " + out.substr(0, 300));
  const nlohmann::json j = nlohmann::json::parse(out.substr(brace));
  ProcessEval e;
  e.fitness = j["fitness"].is_number() ? j["fitness"].get<double>() : std::nan("");
  e.cpu_seconds = j["cpu_seconds"].get<double>();
  e.status = j["status"].get<std::string>();
  e.simd = j.value("simd", "");
  e.voxels = j["voxels"].get<int>();
  e.steps = j["steps"].get<long long>();
  return e;
}

// "5f3b920b7688" from "softevo 0.1.0 (commit 5f3b920b7688)"; "unknown" otherwise.
std::string commit_of(const std::string& exe) {
  const std::string out = capture(shell_quote(exe) + " --version 2>/dev/null").first;
  const std::size_t at = out.find("(commit ");
  if (at == std::string::npos) return "unknown";
  const std::size_t end = out.find(')', at);
  return out.substr(at + 8, end == std::string::npos ? std::string::npos : end - at - 8);
}

// The CPU as /proc/cpuinfo names it (x86: model name, family and model numbers).
std::string cpu_description() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, name, family, model;
  auto value = [](const std::string& l) {
    const std::size_t c = l.find(':');
    std::string v = c == std::string::npos ? "" : l.substr(c + 1);
    v.erase(0, v.find_first_not_of(" \t"));
    return v;
  };
  while (std::getline(in, line)) {
    if (name.empty() && line.rfind("model name", 0) == 0) name = value(line);
    if (family.empty() && line.rfind("cpu family", 0) == 0) family = value(line);
    if (model.empty() && line.rfind("model\t", 0) == 0) model = value(line);
  }
  if (name.empty()) return "unknown";
  return family.empty() ? name : name + " (family " + family + " model " + model + ")";
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

int run_bench_ab(const BenchEvalArgs& a, const std::vector<ChampionRow>& rows) {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  if (!std::filesystem::exists(a.baseline))
    throw std::runtime_error("--baseline " + a.baseline + ": no such file");
  const std::string base_commit = commit_of(a.baseline);
  std::fprintf(stderr,
               "A/B: baseline %s (commit %s) against this build (commit %s), %zu robots, %d "
               "run(s) each, interleaved\n",
               a.baseline.c_str(), base_commit.c_str(), git_commit(), rows.size(), a.runs);
  struct Row {
    std::string name;
    ProcessEval base, ours;                     // fastest run of each build
    double base_slowest = 0, ours_slowest = 0;  // CPU seconds of each build's slowest run
  };
  std::vector<Row> out;
  for (const ChampionRow& r : rows) {
    Row row{r.robot.name.empty() ? r.file : r.robot.name, {}, {}};
    for (int run = 0; run < a.runs; ++run) {
      ProcessEval e[2];  // [0] baseline, [1] this build
      for (int turn = 0; turn < 2; ++turn) {
        const int which = run % 2 == 0 ? turn : 1 - turn;
        e[which] = eval_process(which == 0 ? a.baseline : self, r.file, a);
      }
      const ProcessEval& first = run == 0 ? e[0] : row.base;
      for (const ProcessEval& x : e)
        if (!same_bits(x.fitness, first.fitness) || x.steps != first.steps)
          throw std::runtime_error(r.file + ": the builds (or runs) gave different results: " +
                                   "fitness " + std::to_string(x.fitness) + " vs " +
                                   std::to_string(first.fitness) + " (not the same bits)");
      if (run == 0 || e[0].cpu_seconds < row.base.cpu_seconds) row.base = e[0];
      if (run == 0 || e[1].cpu_seconds < row.ours.cpu_seconds) row.ours = e[1];
      row.base_slowest = std::max(row.base_slowest, e[0].cpu_seconds);
      row.ours_slowest = std::max(row.ours_slowest, e[1].cpu_seconds);
    }
    std::fprintf(stderr, "  %-16s baseline %.2f s, this build %.2f s CPU (%.2fx)\n",
                 row.name.c_str(), row.base.cpu_seconds, row.ours.cpu_seconds,
                 row.base.cpu_seconds / row.ours.cpu_seconds);
    out.push_back(row);
  }
  std::vector<double> ratio;
  std::size_t worst = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    ratio.push_back(out[i].base.cpu_seconds / out[i].ours.cpu_seconds);
    if (ratio[i] < ratio[worst]) worst = i;
  }
  const double med = validation::median(ratio);
  // With several runs, how much one build's runs of one robot differ (slowest / fastest - 1):
  // on a shared machine the same binary varies by up to 20% (docs/scaling.md), and a speed-up
  // within this spread says nothing.
  std::vector<double> spread;
  if (a.runs > 1)
    for (const Row& r : out)
      for (const auto& [fastest, slowest] : {std::pair{r.base.cpu_seconds, r.base_slowest},
                                             std::pair{r.ours.cpu_seconds, r.ours_slowest}})
        if (fastest > 0) spread.push_back(slowest / fastest - 1.0);
  const double spread_median = spread.empty() ? 0.0 : validation::median(spread);
  const double spread_max = spread.empty() ? 0.0 : *std::max_element(spread.begin(), spread.end());
  const std::string cpu = cpu_description();
  if (!a.csv.empty()) {
    const bool fresh = !std::filesystem::exists(a.csv) || std::filesystem::file_size(a.csv) == 0;
    std::ofstream f(a.csv, std::ios::app);
    if (!f) throw std::runtime_error("--csv " + a.csv + ": cannot open for appending");
    if (fresh)
      f << "date_utc,cpu,simd,commit,baseline_commit,integrator,runs,robot,voxels,steps,status,"
           "baseline_cpu_seconds,cpu_seconds,speedup\n";
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    ::gmtime_r(&now, &tm);
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &tm);
    for (std::size_t i = 0; i < out.size(); ++i) {
      const Row& r = out[i];
      char nums[96];
      std::snprintf(nums, sizeof nums, "%.3f,%.3f,%.3f", r.base.cpu_seconds, r.ours.cpu_seconds,
                    ratio[i]);
      f << date << ',' << csv_field(cpu) << ',' << r.ours.simd << ',' << git_commit() << ','
        << base_commit << ',' << a.integrator << ',' << a.runs << ',' << csv_field(r.name) << ','
        << r.ours.voxels << ',' << r.ours.steps << ',' << r.ours.status << ',' << nums << '\n';
    }
    if (!f) throw std::runtime_error("--csv " + a.csv + ": write failed");
  }
  if (a.json) {
    nlohmann::ordered_json j;
    j["cpu"] = cpu;
    j["commit"] = git_commit();
    j["baseline"] = a.baseline;
    j["baseline_commit"] = base_commit;
    j["integrator"] = a.integrator;
    j["runs"] = a.runs;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < out.size(); ++i)
      list.push_back({{"name", out[i].name},
                      {"status", out[i].ours.status},
                      {"fitness", out[i].ours.fitness},
                      {"voxels", out[i].ours.voxels},
                      {"steps", out[i].ours.steps},
                      {"simd", out[i].ours.simd},
                      {"baseline_cpu_seconds", out[i].base.cpu_seconds},
                      {"cpu_seconds", out[i].ours.cpu_seconds},
                      {"speedup", ratio[i]}});
    j["per_robot"] = list;
    j["median_speedup"] = med;
    j["worst_robot"] = out[worst].name;
    j["worst_speedup"] = ratio[worst];
    if (!spread.empty()) {
      j["run_spread_median"] = spread_median;
      j["run_spread_max"] = spread_max;
    }
    std::printf("%s\n", j.dump(1).c_str());
    return kExitOk;
  }
  std::printf("CPU: %s; this build %s (SIMD %s), baseline %s; fastest of %d interleaved runs\n",
              cpu.c_str(), git_commit(), out.front().ours.simd.c_str(), base_commit.c_str(),
              a.runs);
  std::printf("%-16s %6s %7s %12s %9s %8s  %s\n", "robot", "voxels", "steps", "baseline[s]",
              "this[s]", "speedup", "status");
  for (std::size_t i = 0; i < out.size(); ++i)
    std::printf("%-16s %6d %7lld %12.2f %9.2f %7.2fx  %s\n", out[i].name.c_str(),
                out[i].ours.voxels, out[i].ours.steps, out[i].base.cpu_seconds,
                out[i].ours.cpu_seconds, ratio[i], out[i].ours.status.c_str());
  std::printf(
      "\nmedian speed-up %.2fx; worst robot %s %.2fx (CPU seconds, baseline / this build)\n", med,
      out[worst].name.c_str(), ratio[worst]);
  if (!spread.empty())
    std::printf(
        "run-to-run spread of one build on one robot (slowest / fastest run - 1): median %.1f%%, "
        "largest %.1f%%; a speed-up within it is noise\n",
        100.0 * spread_median, 100.0 * spread_max);
  return kExitOk;
}

int run_bench_eval(const BenchEvalArgs& a) {
  std::vector<ChampionRow> rows;
  for (const std::string& f : validation::robot_files(a.dir)) {
    // The gait robots (those whose controller fits the gait task) that --only selects, and
    // the files that --with names, whatever --only says (`--only gait- --with dir-open-09`).
    const bool with = std::any_of(a.with.begin(), a.with.end(), [&](const std::string& w) {
      return f.find(w) != std::string::npos;
    });
    if (!with && !a.only.empty() && f.find(a.only) == std::string::npos) continue;
    ChampionRow row = validation::load_champion(f);
    if (with || tasks::default_task_for(row.robot.controller.task_inputs()) == TaskKind::gait)
      rows.push_back(std::move(row));
  }
  if (rows.empty()) throw std::runtime_error(a.dir + ": no gait robot files selected");
  if (!a.baseline.empty()) return run_bench_ab(a, rows);
  std::fprintf(stderr,
               "benchmarking %zu gait evaluations on %d thread(s), integrator %s, best of %d "
               "run(s)\n",
               rows.size(), a.jobs, a.integrator.c_str(), a.runs);
  const std::vector<ChampionRow> unevaluated = rows;
  for (int run = 1; run <= a.runs; ++run) {
    std::vector<ChampionRow> again = unevaluated;
    validation::evaluate_champions(again, a.overrides,
                                   parse_choice<Integrator>(a.integrator, "--integrator"), a.jobs,
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
  if (ref.empty()) {  // robots without a thesis time (`--with` files, the shipped robots/)
    std::printf(
        "\nmedian CPU seconds: ours %.2f (no robot carries a thesis simulator time); median "
        "%.3f us per voxel-step (thesis 0.65)\n",
        med_ours, validation::median(us_per_voxel_step));
  } else {
    std::printf(
        "\nmedian CPU seconds: ours %.2f, thesis simulator %.2f (%zu of %zu robots); median "
        "speed-up %.2fx (goal >= 5x); median %.3f us per voxel-step (thesis 0.65)\n",
        med_ours, med_ref, ref.size(), rows.size(), med_speedup,
        validation::median(us_per_voxel_step));
  }
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
      ->check(CLI::IsMember(choice_names<Integrator>()));
  cmd->add_option("--only", a->only, "only files whose path contains this text");
  cmd->add_option("--runs", a->runs,
                  "evaluations per robot; the fastest is kept (all must give the same fitness)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--set", a->overrides, "override a config key: section.key=value");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->add_option("--baseline", a->baseline,
                  "another build's softevo: A/B of the two builds, interleaved, per robot");
  cmd->add_option("--with", a->with,
                  "also robot files of any task whose path contains this (with or without --only)");
  cmd->add_option("--csv", a->csv, "with --baseline: append one row per robot to this CSV file");
  cmd->callback([&exit_code, a] { exit_code = run_bench_eval(*a); });
}

}  // namespace softevo::cli
