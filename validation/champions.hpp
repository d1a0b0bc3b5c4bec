// Validation against reference robots: a directory of robot files with their `reference`
// values (e.g. the thesis champions: tests/reference_data.hpp) evaluated in parallel, and the
// rank statistics that compare them. Shared by `softevo champions` and `softevo bench eval`.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"

namespace softevo::validation {

struct ChampionRow {
  std::string file;
  RobotFile robot;
  // From robot.reference (never interpreted by the reader; read here for the comparison).
  bool has_reference = false;
  double ref_fitness = 0.0;
  bool ref_killed = false;
  double ref_cpu_seconds = 0.0;  // thesis simulator CPU time of one 10 s gait evaluation [s]
  std::vector<double> ref_per_direction;
  // Ours.
  EvalResult result;
  double cpu_seconds = 0.0;  // summed thread CPU time of this robot's evaluations [s]
};

// *.json files of `dir`, sorted by name. Throws if the directory does not exist.
std::vector<std::string> robot_files(const std::string& dir);

ChampionRow load_champion(const std::string& path);

// Config of a champion: built-in defaults (+ overrides), task.control from the controller,
// task.kind the task its controller's inputs fit (tasks::default_task_for), integrator as given.
Config champion_config(const ChampionRow& row, const std::vector<std::string>& overrides,
                       Integrator integrator);

// Evaluates every row (every work unit of its task on its own, combined by the task) on `jobs`
// threads; `progress` is called (serialised) when a robot is complete.
void evaluate_champions(std::vector<ChampionRow>& rows, const std::vector<std::string>& overrides,
                        Integrator integrator, int jobs,
                        const std::function<void(const ChampionRow&)>& progress);

// Spearman rank correlation (average ranks for ties); NaN for fewer than 2 values.
double spearman(const std::vector<double>& x, const std::vector<double>& y);
double median(std::vector<double> v);

}  // namespace softevo::validation
