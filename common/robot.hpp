// The robot file `softevo.robot/1` (docs/model.md §10) as plain data, plus its strict reader
// and writer (robot_file.cpp). What `softevo eval` reads and `softevo export` writes.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"  // DistanceInput
#include "common/safe_write.hpp"

namespace softevo {

// The 9 named controller vectors of docs/model.md §4.4, in canonical order. The same layout
// carries the values and (in the genome) their per-gene mutation step sizes.
struct ControllerVectors {
  std::vector<double> weights_hidden;          // n_in*H,  index c*H + i: input c -> hidden i
  std::vector<double> bias_hidden;             // H
  std::vector<double> weights_out;             // H*n_out, index c*n_out + k: hidden c -> out k
  std::vector<double> bias_out;                // n_out
  std::vector<double> weights_recurrent;       // H*H,     index c*H + i: context c -> hidden i
  std::vector<double> weights_recurrent_self;  // H (diagonal context -> context)
  std::vector<double> weights_context;         // H (diagonal hidden -> context)
  std::vector<double> bias_context;            // H
  std::vector<double> freq;                    // 1: oscillator frequency [Hz]
};

// Controller input layout (§4.1): [sin, cos, task inputs, pressure sensors]; the task inputs
// are the task's (tasks/task.hpp, e.g. the direction sensor of the directed task), the pressure
// sensors those of a closed-loop controller (10 slots, one per possible chamber). Without
// oscillator inputs (controller.oscillator_inputs = false) sin and cos are absent.
constexpr int kOscillatorInputs = 2;
constexpr int kPressureSensorInputs = 10;
constexpr int controller_input_count(int task_inputs, bool closed_loop,
                                     bool oscillator_inputs = true) {
  return (oscillator_inputs ? kOscillatorInputs : 0) + task_inputs +
         (closed_loop ? kPressureSensorInputs : 0);
}

struct ControllerSpec {
  std::string kind = "elman";
  bool closed_loop = false;  // "control": "closed" feeds chamber pressures (§4.1)
  // Robot file format 1 records the controller's task inputs as this flag: true = one task
  // input (the direction sensor of the directed task, §7.3), false = none.
  bool directed = false;
  // false: no sin/cos inputs (thesis 5.3.4; the robot file's optional "oscillator_inputs").
  bool oscillator_inputs = true;
  int hidden = 4;
  int outputs = 20;
  ControllerVectors vectors;  // freq[0] = frequency [Hz]
  int task_inputs() const { return directed ? 1 : 0; }
  int input_count() const {
    return controller_input_count(task_inputs(), closed_loop, oscillator_inputs);
  }
  int oscillator_input_count() const { return oscillator_inputs ? kOscillatorInputs : 0; }
  double frequency() const { return vectors.freq.empty() ? 0.0 : vectors.freq[0]; }
};

struct CppnNodeRecord {
  int key = 0;
  double bias = 0.0;
  double response = 1.0;
  std::string activation;  // sigmoid sin abs square exp clamped gauss (tanh for tests)
  std::string aggregation = "sum";
};

struct CppnConnectionRecord {
  int in = 0;
  int out = 0;
  double weight = 0.0;
  bool enabled = true;
};

// Optional "genome" section: what the body was developed from.
struct RobotGenomeRecord {
  std::vector<CppnNodeRecord> nodes;              // input keys -1..-4 are implicit
  std::vector<CppnConnectionRecord> connections;  // in summation order
  ControllerVectors controller_step_sizes;
  std::vector<int> body_lattice = {10, 10, 10};
  DistanceInput distance_input = DistanceInput::pneuvox;
};

// Optional "evaluation" section: the settings of the run the robot was exported from, so that
// `softevo eval`, `render` and the Python package reproduce its archived fitness by default
// (docs/model.md §10). The config text is the archive's /config verbatim.
struct RobotEvaluation {
  std::string config;           // canonical TOML text of the run's config
  std::string config_hash;      // 16 hex digits, text_hash(config) (checked on read)
  std::string experiment_hash;  // 16 hex digits, experiment_hash_of_text(config) (checked)
  std::string run;              // the archive it came from, as given to export ("" unknown)
  std::optional<std::int64_t> generation;
  std::optional<std::int64_t> id;
  std::optional<double> fitness;  // archived fitness (what a re-evaluation must give)
  std::string status;             // archived status ("ok", "killed: flipped", ...; "" unknown)
};

struct RobotFile {
  std::string name;
  BodyPlan body;  // lattice, cells, materials (defaults E = 10 kPa x k, 1000 kg/m^3), voxel size
  ControllerSpec controller;
  std::optional<RobotGenomeRecord> genome;
  std::optional<RobotEvaluation> evaluation;
  std::string reference_json;  // "reference" object verbatim (never interpreted), "" if absent
};

// Strict reader: unknown keys, wrong types, wrong lengths are a RobotFileError naming the file,
// the key and the problem.
class RobotFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
RobotFile read_robot_file(const std::string& path);
RobotFile parse_robot_json(const std::string& json_text, const std::string& source_name);
std::string robot_to_json(const RobotFile& robot);  // pretty JSON, full double precision
// Atomic, refuses symlinks and special files (common/safe_write.hpp); an existing regular file
// is replaced unless `overwrite` is refuse (the CLI's default; --force replaces).
void write_robot_file(const RobotFile& robot, const std::string& path,
                      Overwrite overwrite = Overwrite::replace);

}  // namespace softevo
