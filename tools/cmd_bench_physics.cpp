// `softevo bench physics [--json] [--steps N] [--runs R] [--scene NAME] [--simd W]`: raw physics
// speed (issue 3). Named scenes of 1 cm voxels, E = 100 kPa, the thesis material settings, floor,
// gravity and self-collision on (the scenes the thesis system's raw-physics speed was measured on),
// for both integrators; `--scene blockXxYxZ` measures a solid block of any size. Each figure is
// the best of R runs of N steps from the initial state, in CPU seconds of this thread (the machine
// is shared; wall time is printed alongside). With --cycles
// the core's clock is measured (bench_common.hpp) before and after the scenes, and each figure
// is also given in cycles per voxel-step at the mean of the two readings, the unit in which
// docs/scaling.md compares the step with the core's arithmetic bound.
//
// --batch measures the batched step (physics/batch.hpp, issue 40): K evaluations of one body in
// the lanes of one step, K = 1, 4, 5, 8, 10, 16, each figure in microseconds per voxel-step per
// evaluation (and its gain over K = 1, which is the one-robot step itself). The lanes start from
// different states of one body: a block's states every 20 steps from rest, or (--robot FILE) the
// robot's own evaluation every 3 control frames from frame 10 (worker/evaluation_states.hpp); no
// external force.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/robot.hpp"
#include "physics/batch.hpp"
#include "physics/model.hpp"
#include "physics/scenes.hpp"
#include "physics/step.hpp"
#include "tools/bench_common.hpp"
#include "tools/commands.hpp"
#include "worker/evaluation_states.hpp"

namespace softevo::cli {

namespace {

struct Scene {
  std::string name;
  int x, y, z;
};

// The scenes run by default (and selected by a part of their name with --scene).
const Scene kNamedScenes[] = {
    {"block10x10x10", 10, 10, 10}, {"block4x4x4", 4, 4, 4}, {"beam10x2x2", 10, 2, 2}};

// The largest block of --scene blockXxYxZ: a block of 10^5 voxels takes about 170 MB and
// 15 ms per step.
constexpr long long kMaxBlockVoxels = 100000;

// --scene blockXxYxZ (X, Y, Z decimal digits): that solid block, for measuring how the step's
// cost per voxel depends on the body's size (docs/scaling.md); nothing if the text has another
// form. A side of 0 or beyond the block limit is left to the caller's range check.
std::optional<Scene> parse_block_scene(const std::string& text) {
  constexpr std::string_view kPrefix = "block";
  if (text.rfind(kPrefix, 0) != 0) return std::nullopt;
  long long side[3] = {0, 0, 0};
  const char* p = text.data() + kPrefix.size();
  const char* const end = text.data() + text.size();
  for (int k = 0; k < 3; ++k) {
    if (k > 0) {
      if (p == end || *p != 'x') return std::nullopt;
      ++p;
    }
    if (p == end || *p < '0' || *p > '9') return std::nullopt;  // no sign, no space
    const auto [next, error] = std::from_chars(p, end, side[k]);
    if (error == std::errc::result_out_of_range)
      side[k] = kMaxBlockVoxels + 1;
    else if (error != std::errc())
      return std::nullopt;
    p = next;
  }
  if (p != end) return std::nullopt;
  const auto clamp = [](long long v) { return static_cast<int>(std::min(v, kMaxBlockVoxels + 1)); };
  return Scene{text, clamp(side[0]), clamp(side[1]), clamp(side[2])};
}

struct BenchRow {
  std::string scene, integrator, simd;
  int voxels = 0, links = 0, steps = 0, failed_steps = 0;
  int lanes = 1;  // evaluations per step (--batch)
  double cpu_seconds = 0.0, wall_seconds = 0.0;
  // per evaluation
  double us_per_voxel_step() const {
    return cpu_seconds * 1e6 / (static_cast<double>(steps) * voxels * lanes);
  }
  double cycles_per_voxel_step(double clock_hz) const {
    return us_per_voxel_step() * 1e-6 * clock_hz;
  }
};

// The core's clock [Hz] read before and after the scenes (--cycles); the clock may move while
// they run, so the cycles are given at the mean of the two readings and both are printed.
// The operating system's figure, where it has one, is printed beside it as a cross-check.
struct CoreClock {
  double before_hz = 0.0, after_hz = 0.0;
  std::optional<double> os_hz;
  double mean_hz() const { return 0.5 * (before_hz + after_hz); }
  // The two figures disagree when they are more than 10% apart: on a VM the OS often reports the
  // nominal or the TSC rate, on a laptop a rate of a moment ago.
  bool os_disagrees() const { return os_hz && std::fabs(*os_hz - mean_hz()) > 0.1 * mean_hz(); }
};

void print_header(bool with_cycles) {
  std::printf("%-14s %-10s %-6s %5s %6s %6s %12s %14s %10s %8s", "scene", "integrator", "simd",
              "lanes", "voxels", "links", "us/vox-step", "steps/second", "wall/cpu", "failed");
  std::printf(with_cycles ? " %12s\n" : "\n", "cycles/v-s");
}

// One table row, with cycles per voxel-step at clock_hz when given.
void print_row(const BenchRow& r, std::optional<double> clock_hz) {
  std::printf("%-14s %-10s %-6s %5d %6d %6d %12.4f %14.1f %10.2f %8d", r.scene.c_str(),
              r.integrator.c_str(), r.simd.c_str(), r.lanes, r.voxels, r.links,
              r.us_per_voxel_step(), r.steps / r.cpu_seconds, r.wall_seconds / r.cpu_seconds,
              r.failed_steps);
  if (clock_hz) std::printf(" %12.1f", r.cycles_per_voxel_step(*clock_hz));
  std::printf("\n");
  std::fflush(stdout);
}

// The fastest of `runs` runs into row (CPU seconds, wall seconds, failed steps): prepare() sets a
// run up outside the clock and returns the run, a callable that steps and returns its failed
// steps.
template <class Prepare>
void keep_best_run(BenchRow& row, int runs, Prepare&& prepare) {
  row.cpu_seconds = 1e300;
  for (int r = 0; r < runs; ++r) {
    auto run = prepare();
    const double c0 = thread_cpu_seconds(), w0 = wall_seconds();
    const int failed = run();
    const double cpu = thread_cpu_seconds() - c0, wall = wall_seconds() - w0;
    if (cpu < row.cpu_seconds) {
      row.cpu_seconds = cpu;
      row.wall_seconds = wall;
      row.failed_steps = failed;
    }
  }
}

BenchRow bench_one(const Scene& scene, Integrator integrator, physics::Simd simd, int steps,
                   int runs) {
  PhysicsConfig cfg;  // thesis defaults: floor, gravity, self-collision, damping 0.1/0.001/0.1
  cfg.integrator = integrator;
  physics::BuildOptions options;
  options.simd = simd;
  const physics::Model model =
      physics::build_model(physics::solid_block(scene.x, scene.y, scene.z, 1.0e5), cfg, options);
  BenchRow row{scene.name,        to_string(integrator), softevo::to_string(model.simd),
               model.voxel_count, model.link_count,      steps};
  keep_best_run(row, runs, [&] {
    return [&model, steps, state = physics::initial_state(model),
            scratch = physics::make_scratch(model)]() mutable {
      int failed = 0;
      for (int i = 0; i < steps; ++i)
        failed += physics::step(model, state, scratch) != physics::StepStatus::ok;
      return failed;
    };
  });
  return row;
}

// The lane counts of --batch.
constexpr int kBatchLanes[] = {1, 4, 5, 8, 10, 16};

// The starting states of --batch: kMaxBatchLanes states of one body (see the header).
struct BatchScene {
  std::string name;
  physics::Model model;
  std::vector<physics::State> states;
};
BatchScene block_batch_scene(const Scene& scene) {
  BatchScene b{
      scene.name,
      physics::build_model(physics::solid_block(scene.x, scene.y, scene.z, 1.0e5), PhysicsConfig{}),
      {}};
  physics::State s = physics::initial_state(b.model);
  physics::Scratch sc = physics::make_scratch(b.model);
  for (int k = 0; k < physics::kMaxBatchLanes; ++k) {
    b.states.push_back(s);
    for (int i = 0; i < 20; ++i) physics::step(b.model, s, sc);
  }
  return b;
}

// K lanes of `scene` stepped together: the best of `runs` runs of `steps` steps.
BenchRow bench_batch(const BatchScene& scene, physics::Simd simd, int lanes, int steps, int runs) {
  physics::Model model = scene.model;
  model.simd = simd;
  const std::vector<physics::State> states(scene.states.begin(), scene.states.begin() + lanes);
  BenchRow row{scene.name,
               to_string(model.integrator),
               softevo::to_string(model.simd),
               model.voxel_count,
               model.link_count,
               steps};
  row.lanes = lanes;
  std::vector<physics::StepStatus> status(static_cast<std::size_t>(lanes));
  keep_best_run(row, runs, [&] {
    physics::BatchState batch = physics::make_batch_state(model, states);
    physics::BatchScratch scratch = physics::make_batch_scratch(model, batch);
    return
        [&model, &status, steps, batch = std::move(batch), scratch = std::move(scratch)]() mutable {
          int failed = 0;
          for (int i = 0; i < steps; ++i) {
            physics::step_batch(model, batch, scratch, {}, status);
            for (physics::StepStatus st : status) failed += st != physics::StepStatus::ok;
          }
          return failed;
        };
  });
  return row;
}

}  // namespace

void register_bench_physics(CLI::App& app, int& exit_code) {
  CLI::App* bench = bench_group(app);
  auto* cmd = bench->add_subcommand(
      "physics", "microseconds per voxel-step of the voxel physics on named scenes");
  auto json = std::make_shared<bool>(false);
  auto steps = std::make_shared<int>(3000);
  auto runs = std::make_shared<int>(3);
  auto only = std::make_shared<std::string>();
  auto cycles = std::make_shared<bool>(false);
  auto batch = std::make_shared<bool>(false);
  auto robot_file = std::make_shared<std::string>();
  cmd->add_flag("--json", *json, "print a JSON list of result objects");
  cmd->add_flag("--batch", *batch,
                "the batched step: 1, 4, 5, 8, 10 and 16 evaluations of one body per step, "
                "microseconds per voxel-step per evaluation (pneuvox)");
  cmd->add_option("--robot", *robot_file,
                  "with --batch: also this robot file's body, its lanes from its own evaluation")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--cycles", *cycles,
                "measure the core's clock (a chain of dependent register additions, cross-checked "
                "with the OS's figure) and add cycles per voxel-step");
  cmd->add_option("--steps", *steps, "steps per run (default 3000)")->check(at_least(1));
  cmd->add_option("--runs", *runs, "runs per figure, best is kept (default 3)")->check(at_least(1));
  cmd->add_option("--scene", *only,
                  "only scenes whose name contains this; or a solid block of any size, "
                  "blockXxYxZ (e.g. block6x6x6)");
  auto simd_name = std::make_shared<std::string>("best");
  std::vector<std::string> simd_choices = physics::simd_names();
  simd_choices.emplace_back("all");
  std::string simd_help = "SIMD width of the step passes:";
  for (const std::string& name : simd_choices) simd_help += " " + name;
  simd_help += " (default best; results are bit-identical, only the speed differs)";
  cmd->add_option("--simd", *simd_name, simd_help)->check(CLI::IsMember(simd_choices));
  cmd->callback([&exit_code, json, steps, runs, only, simd_name, cycles, batch, robot_file] {
    std::vector<physics::Simd> widths;
    if (*simd_name == "all") {
      for (physics::Simd s : physics::simd_widths())
        if (physics::simd_supported(s)) widths.push_back(s);
    } else {
      // the name is checked by IsMember
      widths.push_back(physics::resolve_simd(physics::parse_simd(*simd_name).value()));
    }
    for (physics::Simd s : widths) {
      if (!physics::simd_supported(s)) {
        std::fprintf(stderr,
                     "softevo bench physics: --simd %s is not supported by this CPU or build\n",
                     softevo::to_string(s));
        exit_code = kExitUsage;
        return;
      }
    }
    std::optional<CoreClock> clock;
    if (*cycles) {
      const std::optional<double> before = measure_core_clock_hz();
      if (!before) {
        std::fprintf(stderr,
                     "softevo bench physics: --cycles measures the clock on x86-64 and AArch64 "
                     "only\n");
        exit_code = kExitUsage;
        return;
      }
      clock = CoreClock{*before, 0.0, os_core_clock_hz()};
    }
    std::vector<Scene> scenes;
    for (const Scene& named : kNamedScenes)
      if (only->empty() || named.name.find(*only) != std::string::npos) scenes.push_back(named);
    if (scenes.empty()) {
      const std::optional<Scene> block = parse_block_scene(*only);
      if (!block) {
        std::string names;
        for (const Scene& named : kNamedScenes) names += (names.empty() ? "" : ", ") + named.name;
        std::fprintf(stderr,
                     "softevo bench physics: --scene %s matches no scene (%s) and is not a block "
                     "of the form blockXxYxZ\n",
                     only->c_str(), names.c_str());
        exit_code = kExitUsage;
        return;
      }
      const long long voxels = 1LL * block->x * block->y * block->z;
      if (block->x < 1 || block->y < 1 || block->z < 1 || voxels > kMaxBlockVoxels) {
        std::fprintf(stderr,
                     "softevo bench physics: --scene %s: each side must be at least 1 and the "
                     "block at most %lld voxels\n",
                     only->c_str(), kMaxBlockVoxels);
        exit_code = kExitUsage;
        return;
      }
      scenes.push_back(*block);
    }
    // Without --cycles each row is printed as it is measured; with it, once the clock is known.
    if (!*json && !*cycles) print_header(false);
    if (!robot_file->empty() && !*batch) {
      std::fprintf(stderr, "softevo bench physics: --robot needs --batch\n");
      exit_code = kExitUsage;
      return;
    }
    std::vector<BenchRow> rows;
    if (*batch) {
      std::vector<BatchScene> batch_scenes;
      for (const Scene& scene : scenes) batch_scenes.push_back(block_batch_scene(scene));
      if (!robot_file->empty()) {
        try {
          const RobotFile robot = read_robot_file(*robot_file);
          worker::EvaluationStates e =
              worker::evaluation_states(robot, physics::kMaxBatchLanes, 10, 3);
          if (static_cast<int>(e.states.size()) < physics::kMaxBatchLanes)
            throw std::invalid_argument("its evaluation ends before frame " +
                                        std::to_string(10 + 3 * (physics::kMaxBatchLanes - 1)));
          batch_scenes.push_back({robot.name, std::move(e.model), std::move(e.states)});
        } catch (const std::exception& e) {
          std::fprintf(stderr, "softevo bench physics: --robot %s: %s\n", robot_file->c_str(),
                       e.what());
          exit_code = kExitUsage;
          return;
        }
      }
      for (const BatchScene& scene : batch_scenes)
        for (physics::Simd simd : widths)
          for (int lanes : kBatchLanes) {
            rows.push_back(bench_batch(scene, simd, lanes, *steps, *runs));
            if (!*json && !*cycles) print_row(rows.back(), std::nullopt);
          }
    } else {
      for (const Scene& scene : scenes) {
        for (Integrator integrator : {Integrator::pneuvox, Integrator::symplectic})
          for (physics::Simd simd : widths) {
            rows.push_back(bench_one(scene, integrator, simd, *steps, *runs));
            if (!*json && !*cycles) print_row(rows.back(), std::nullopt);
          }
      }
    }
    if (clock) {
      clock->after_hz = measure_core_clock_hz().value();
      if (!*json) {
        print_header(true);
        for (const BenchRow& r : rows) print_row(r, clock->mean_hz());
        std::printf(
            "core clock %.3f GHz: dependent register additions, %.3f before and %.3f after\n",
            clock->mean_hz() * 1e-9, clock->before_hz * 1e-9, clock->after_hz * 1e-9);
        if (!clock->os_hz)
          std::printf("the operating system gives no clock figure to cross-check it\n");
        else if (clock->os_disagrees())
          std::printf(
              "the operating system says %.3f GHz, %.0f%% from the measured clock: the cycles use "
              "the measured one (a VM's figure is often the nominal or TSC rate)\n",
              *clock->os_hz * 1e-9, 100.0 * (*clock->os_hz / clock->mean_hz() - 1.0));
        else
          std::printf("the operating system agrees: %.3f GHz\n", *clock->os_hz * 1e-9);
      }
    }
    nlohmann::json out = nlohmann::json::array();
    int failed = 0;
    for (const BenchRow& r : rows) {
      const double us = r.us_per_voxel_step();
      const double sps = r.steps / r.cpu_seconds;
      failed += r.failed_steps;
      if (*json) {
        out.push_back({{"scene", r.scene},
                       {"integrator", r.integrator},
                       {"simd", r.simd},
                       {"voxels", r.voxels},
                       {"links", r.links},
                       {"steps", r.steps},
                       {"lanes", r.lanes},
                       {"runs", *runs},
                       {"us_per_voxel_step", us},
                       {"steps_per_second", sps},
                       {"cpu_seconds", r.cpu_seconds},
                       {"wall_seconds", r.wall_seconds},
                       {"failed_steps", r.failed_steps}});
        if (clock) {
          out.back()["clock_ghz"] = clock->mean_hz() * 1e-9;
          out.back()["clock_ghz_before"] = clock->before_hz * 1e-9;
          out.back()["clock_ghz_after"] = clock->after_hz * 1e-9;
          out.back()["clock_method"] = "dependent register additions";
          out.back()["clock_ghz_os"] =
              clock->os_hz ? nlohmann::json(*clock->os_hz * 1e-9) : nlohmann::json(nullptr);
          out.back()["clock_os_disagrees"] = clock->os_disagrees();
          out.back()["cycles_per_voxel_step"] = r.cycles_per_voxel_step(clock->mean_hz());
        }
      }
    }
    if (*json) std::printf("%s\n", out.dump(2).c_str());
    exit_code = failed == 0 ? kExitOk : kExitMismatch;
  });
}

}  // namespace softevo::cli
