#include "worker/evaluate_unit.hpp"

#include <cmath>
#include <cstdlib>
#include <exception>
#include <string>

#include "evo/development.hpp"
#include "worker/evaluate_robot.hpp"

namespace softevo::worker {
namespace {

// Thrown from the per-frame observer when the wall-clock budget is spent; evaluate_robot turns
// every exception into status `failed`, so the flag below tells a timeout apart.
struct EvaluationTimeout : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// SOFTEVO_TEST_FAIL_GENOME=<id>: test-only hook, see the header.
bool test_hook_fails(std::int64_t genome_id) {
  const char* v = std::getenv("SOFTEVO_TEST_FAIL_GENOME");
  if (v == nullptr || *v == '\0') return false;
  char* end = nullptr;
  const long long id = std::strtoll(v, &end, 10);
  return end != v && *end == '\0' && id == genome_id;
}

EvalResult failed_result(const EvalRequest& request, EvalStatus status, std::string message) {
  EvalResult r;
  r.genome_id = request.genome_id;
  r.direction_index = request.direction_index;
  r.status = status;
  r.fitness = 0.0;
  r.message = std::move(message);
  return r;
}

}  // namespace

BuiltRobot build_robot(const Config& config, const evo::Genome& genome) {
  BuiltRobot robot;
  evo::DevelopedBody developed = evo::develop_body(genome.cppn, config.body);
  robot.valid = developed.valid;
  robot.actuatable = developed.actuatable;
  robot.body = std::move(developed.plan);
  robot.body.materials = material_table(config.physics);
  robot.body.voxel_size = config.physics.voxel_size;
  robot.controller = evo::to_controller_spec(genome, config);
  return robot;
}

RobotFile robot_file_of(const Config& config, const evo::Genome& genome, const std::string& name) {
  BuiltRobot robot = build_robot(config, genome);
  RobotFile file;
  file.name = name;
  file.body = std::move(robot.body);
  file.controller = std::move(robot.controller);
  file.genome = evo::to_genome_record(genome, config);
  return file;
}

EvalResult evaluate_unit(const Config& config, std::uint64_t config_hash,
                         const EvalRequest& request, const UnitOptions& options) {
  if (request.config_hash != config_hash)
    throw ConfigMismatch("work unit (generation " + std::to_string(request.generation) +
                         ", genome " + std::to_string(request.genome_id) + ") has config hash " +
                         hash_hex(request.config_hash) + ", this worker has " +
                         hash_hex(config_hash) + ": master and worker run different configs");
  const auto start = std::chrono::steady_clock::now();
  const double budget = config.run.eval_timeout_seconds;  // [s], 0 = no limit
  bool timed_out = false;
  EvalResult result;
  try {
    if (test_hook_fails(request.genome_id))
      throw std::runtime_error("SOFTEVO_TEST_FAIL_GENOME test hook: genome " +
                               std::to_string(request.genome_id));
    const evo::Genome genome = evo::decode_genome(request.genome);
    const BuiltRobot robot = build_robot(config, genome);
    if (!robot.valid || !robot.actuatable) {
      result = failed_result(
          request, EvalStatus::invalid_body,
          robot.valid ? "body has no chamber (not actuatable)" : "body has no structural voxel");
    } else if (options.simulate) {
      result = options.simulate(config, robot, request);
    } else {
      EvalOptions eval_options;
      if (budget > 0.0) {
        // Checked once per control frame (60 Hz of simulated time): cheap, and a runaway
        // evaluation stops within one frame of its budget.
        eval_options.on_frame = [&](const TraceFrame&) {
          const double spent =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          if (spent > budget) {
            timed_out = true;
            throw EvaluationTimeout("evaluation exceeded run.eval_timeout_seconds");
          }
        };
      }
      result = evaluate_robot(config, robot.body, robot.controller, request.direction_index,
                              eval_options);
    }
  } catch (const EvaluationTimeout&) {
    timed_out = true;
  } catch (const std::exception& e) {
    result = failed_result(request, EvalStatus::failed, e.what());
  } catch (...) {
    result = failed_result(request, EvalStatus::failed, "unknown exception");
  }
  if (timed_out) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "evaluation exceeded run.eval_timeout_seconds = %g s", budget);
    result = failed_result(request, EvalStatus::timeout, buf);
  }
  result.genome_id = request.genome_id;
  result.direction_index = request.direction_index;
  // A non-finite fitness is numerical trouble that escaped the physics' own checks.
  if (result.status == EvalStatus::ok && !std::isfinite(result.fitness)) {
    result.status = EvalStatus::diverged;
    result.message = "non-finite fitness";
  }
  if (result.status != EvalStatus::ok) result.fitness = 0.0;  // scored like a killed robot
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace softevo::worker
