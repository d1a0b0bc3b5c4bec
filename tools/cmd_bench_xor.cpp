// `softevo bench xor [--runs N] [--seed S] [--json]`: the NEAT machinery on XOR (issue 5), with
// the NEAT paper's XOR configuration (evo/xor.cpp). Prints the number of runs solved and the mean
// and standard deviation of the evaluations to the first solution; Stanley & Miikkulainen (2002)
// report 100/100 solved, mean 4,755 evaluations (32 generations of 150), sd 2,553.
#include <cstdint>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "evo/xor.hpp"
#include "tools/bench_common.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {

void register_bench_xor(CLI::App& app, int& exit_code) {
  CLI::App* bench = bench_group(app);
  auto* cmd = bench->add_subcommand(
      "xor", "evolve XOR networks with NEAT (paper configuration) over N seeded runs");
  auto runs = std::make_shared<int>(100);
  auto seed = std::make_shared<std::uint64_t>(1);
  auto max_generations = std::make_shared<std::int64_t>(500);
  auto json = std::make_shared<bool>(false);
  cmd->add_option("--runs", *runs, "number of runs (seeds S .. S+N-1)")->check(at_least(1));
  cmd->add_option("--seed", *seed, "first seed");
  cmd->add_option("--max-generations", *max_generations, "give up a run after this many")
      ->check(at_least(1));
  cmd->add_flag("--json", *json, "print one JSON object");
  cmd->callback([&exit_code, runs, seed, max_generations, json] {
    const evo::XorSummary s = evo::run_xor_benchmark(*runs, *seed, *max_generations);
    if (*json) {
      nlohmann::ordered_json j;
      j["runs"] = s.runs;
      j["solved"] = s.solved;
      j["mean_evaluations"] = s.mean_evaluations;
      j["sd_evaluations"] = s.sd_evaluations;
      j["worst_evaluations"] = s.worst_evaluations;
      j["mean_generations"] = s.mean_generations;
      j["mean_hidden_nodes"] = s.mean_hidden_nodes;
      j["mean_enabled_connections"] = s.mean_enabled_connections;
      j["first_seed"] = *seed;
      j["max_generations"] = *max_generations;
      j["criterion"] = "all four outputs on the correct side of 0.5";
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf("XOR (NEAT paper configuration, population 150), seeds %llu..%llu\n",
                  static_cast<unsigned long long>(*seed),
                  static_cast<unsigned long long>(*seed + static_cast<std::uint64_t>(*runs) - 1));
      std::printf("solved:            %d / %d (all four outputs on the correct side of 0.5)\n",
                  s.solved, s.runs);
      std::printf("evaluations:       mean %.1f, sd %.1f, worst %lld (over solved runs)\n",
                  s.mean_evaluations, s.sd_evaluations,
                  static_cast<long long>(s.worst_evaluations));
      std::printf("generations:       mean %.2f\n", s.mean_generations);
      std::printf("solution size:     %.2f hidden nodes, %.2f enabled connections (mean)\n",
                  s.mean_hidden_nodes, s.mean_enabled_connections);
      std::printf("NEAT paper (2002): 100 / 100, mean 4755, sd 2553, 2.35 hidden nodes\n");
    }
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
