// One evaluation run: the main loop of pneuvox-model.md §5 on a built robot.
//
// Per control frame f = 0 .. frames-1 (Appendix B item 1):
//   1. sensors: direction sensor (§7.3, directed controllers), chamber pressures (§3.7, closed
//      loop; frame 0 reads pneumatics.initial_sensor_pressure, SPEC section 3);
//   2. oscillator advance, Elman network, valve commands u = (y + 1)/2 (§4);
//   3. kill checks flipped()/exploded() (§2.15);
//   4. waypoint every `control_rate` frames (§7.2);
//   5. steps_per_frame x (pneumatic update §3.6, physics step §2.12).
// After the loop a final waypoint, then the fitness (§7).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "physics/model.hpp"
#include "physics/quat.hpp"

namespace softevo::worker {

// Plain data of one recorded frame, handed to an observer (e.g. the HDF5 trace writer of
// `softevo eval --trace`). Views are valid only during the call.
struct TraceFrame {
  int frame = 0;      // control frame index; the record after the last frame has index `frames`
  double time = 0.0;  // simulated time at this record [s]
  std::span<const physics::Vec3> positions;     // voxel centres [m] (voxels)
  std::span<const physics::Quat> orientations;  // (w,x,y,z) (voxels)
  std::span<const double> pressures;            // chamber pressure, absolute [Pa] (chambers)
  std::span<const float> valve_commands;        // valve openings in [0,1] (2 x chambers)
  std::span<const float> inputs;                // controller inputs of this frame
};

// Called once before the first frame with the built model (for static trace data).
struct TraceHeader {
  const physics::Model* model = nullptr;
  int chambers = 0;
  int frames = 0;           // control frames planned
  int steps_per_frame = 0;  // physics steps per control frame
};

struct EvalOptions {
  bool ablate_oscillator = false;  // feed 0 to the sin/cos inputs (thesis section 5.1.1)
  bool ablate_sensors = false;     // feed 0 to the pressure-sensor inputs
  // SIMD width of the physics step passes; results are bit-identical for every width
  physics::Simd simd = physics::Simd::best;
  std::function<void(const TraceHeader&)> on_start;  // optional observer
  std::function<void(const TraceFrame&)> on_frame;   // optional observer, 60 Hz
};

// Simulate `plan` driven by `controller` for config.task.eval_seconds. direction_index = -1:
// gait task (§7.1); otherwise the directed task towards config.task.directions[direction_index]
// (§7.2). Never throws for numerical trouble (status); throws std::invalid_argument for a body,
// controller or config that cannot be simulated.
EvalResult simulate(const Config& config, const BodyPlan& plan, const ControllerSpec& controller,
                    int direction_index, const EvalOptions& opts);

}  // namespace softevo::worker
