// One work unit, MPI-free: EvalRequest -> decode genome -> develop body (§6) -> materials from
// the config -> controller -> simulate (§5) -> EvalResult. Used by the MPI worker loop, by the
// single-rank master and by tests.
//
// Failures are results, not crashes: an undecodable genome or an exception anywhere in the
// evaluation gives status `failed` with the message, an evaluation longer than
// run.eval_timeout_seconds gives `timeout`, an invalid or non-actuatable body gives
// `invalid_body`; all of them score like a killed robot (fitness 0, run.on_failure = "killed").
// Only a config-hash mismatch is an error (ConfigMismatch): the worker and the master disagree
// about the experiment, and no result would mean anything.
//
// Test hook (test-only, documented in docs/archive.md): if the environment variable
// SOFTEVO_TEST_FAIL_GENOME is set to a genome id, evaluating that genome throws inside the
// evaluation, exercising the failure path of a real run.
#pragma once

#include <chrono>
#include <functional>
#include <stdexcept>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "evo/genome.hpp"

namespace softevo::worker {

class ConfigMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A genome turned into what the simulator needs.
struct BuiltRobot {
  bool valid = false;       // §6.5: at least one structural cell
  bool actuatable = false;  // §6.5: at least one chamber
  BodyPlan body;            // materials and voxel size filled from the config
  ControllerSpec controller;
};
BuiltRobot build_robot(const Config& config, const evo::Genome& genome);

// The robot file of a genome (body, controller, genome records), named `name`.
RobotFile robot_file_of(const Config& config, const evo::Genome& genome, const std::string& name);

struct UnitOptions {
  // Substitute for the simulator (tests, benchmarks of the scheduling); empty = the real one.
  std::function<EvalResult(const Config&, const BuiltRobot&, const EvalRequest&)> simulate;
};

// `config_hash` must be config_hash(config) (passed in so it is computed once per run).
// Throws ConfigMismatch if request.config_hash differs; never throws otherwise.
EvalResult evaluate_unit(const Config& config, std::uint64_t config_hash,
                         const EvalRequest& request, const UnitOptions& options = {});

}  // namespace softevo::worker
