// Robot -> fitness: the evaluation entry points shared by `softevo eval`, the MPI worker loop
// and the tests. MPI-free, HDF5-free; deterministic (same inputs -> bit-identical result).
#pragma once

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "worker/simulation.hpp"

namespace softevo {

using worker::EvalOptions;

// One evaluation: direction_index = -1 is the gait task (§7.1), otherwise the directed task
// towards config.task.directions[direction_index] (§7.2). Never throws: a body or controller
// that cannot be simulated gives status `failed` (or `invalid_body`) with a message.
EvalResult evaluate_robot(const Config& config, const BodyPlan& plan,
                          const ControllerSpec& controller, int direction_index,
                          const EvalOptions& opts = {});

// The whole task of `config.task.kind`: "gait" -> evaluate_robot(..., -1); "directed" -> one
// evaluation per direction of config.task.directions, combined as §7.4 (sum; any direction not
// ok -> fitness 0). components has one entry per direction.
EvalResult evaluate_task(const Config& config, const BodyPlan& plan,
                         const ControllerSpec& controller, const EvalOptions& opts = {});

}  // namespace softevo
