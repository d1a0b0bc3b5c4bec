// States of a robot's own evaluation (its controller, pneumatics and collisions), for stepping
// several evaluations of one body together (physics/batch.hpp): the batched-step tests and
// `softevo bench physics --batch` take their lanes from here, so that the lanes differ as
// evaluations of one body do (link modes, floor contacts, collision pairs).
#pragma once

#include <vector>

#include "common/robot.hpp"
#include "physics/model.hpp"
#include "physics/state.hpp"

namespace softevo::worker {

struct EvaluationStates {
  physics::Model model;                // the evaluation's Model (SIMD width: best)
  std::vector<physics::State> states;  // in order of simulated time
};

// The robot's gait evaluation (open or closed loop as its controller is, the task its inputs
// name, 10 s, work unit 0): its state at the start of control frames first_frame,
// first_frame + gap_frames, ..., `count` of them or fewer if the evaluation ends first. Throws
// std::invalid_argument for a robot that cannot be simulated.
EvaluationStates evaluation_states(const RobotFile& robot, int count, int first_frame,
                                   int gap_frames);

}  // namespace softevo::worker
