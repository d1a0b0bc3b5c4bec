// The viewer tests' robot: the worker tests' two-chamber block with a complete controller, as a
// view input (no file needed), for the gait or the directed task.
#pragma once

#include <cmath>

#include "common/config.hpp"
#include "scene/scene.hpp"
#include "tests/test_controller_spec.hpp"
#include "tests/worker/two_chamber_block.hpp"
#include "view/session.hpp"

namespace softevo::test {

inline view::ViewInput block_input(TaskKind kind, double seconds) {
  view::ViewInput in;
  in.kind = view::InputKind::robot;
  in.name = "block";
  in.robot.name = "block";
  in.robot.body = two_chamber_block();
  const bool directed = kind == TaskKind::directed;
  in.robot.controller = make_controller(
      true, directed, [](int i) { return std::cos(0.7 + 2.1 * i); }, 2.5);
  in.config.task.kind = kind;
  in.config.task.control = ControlLoop::closed;
  in.config.task.eval_seconds = seconds;
  in.config.run.eval_timeout_seconds = 0.0;
  if (directed) in.config.task.directions = {0.0};
  in.body = scene::body_from_plan(in.robot.body);
  return in;
}

}  // namespace softevo::test
