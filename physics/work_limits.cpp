// The work of one evaluation and its limits. See work_limits.hpp.
#include "physics/work_limits.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "physics/model.hpp"

namespace softevo::physics {
namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

EvaluationWork evaluation_work(float dt_f, double control_rate, double eval_seconds) {
  if (!(control_rate > 0.0) || !std::isfinite(control_rate))
    throw WorkLimitError("task.control_rate = " + number(control_rate) + " Hz must be > 0");
  // §5 step 8: stepsPerFrame = (int)(1.0f / 60.0f / dt) in float arithmetic. The quotient is
  // checked before the conversion: beyond int range the conversion is undefined (it gave 0).
  const float frame_seconds_f = 1.0f / static_cast<float>(control_rate);
  const float steps_f = frame_seconds_f / dt_f;
  const std::string frame_text = "a control frame (" + number(frame_seconds_f) +
                                 " s at task.control_rate = " + number(control_rate) + " Hz)";
  if (!(dt_f > 0.0f) || !(steps_f < static_cast<float>(kMaxStepsPerFrame + 1)))
    throw WorkLimitError(frame_text + " needs " + number(steps_f) +
                         " physics steps of dt = " + number(dt_f) + " s, more than the limit of " +
                         std::to_string(kMaxStepsPerFrame) +
                         " (docs/model.md §5): the voxels are too small or too stiff for their "
                         "mass (voxel size, Young's modulus, density, physics.dt_fraction)");
  EvaluationWork work;
  work.steps_per_frame = static_cast<int>(steps_f);
  if (work.steps_per_frame < 1)
    throw WorkLimitError(frame_text + " is shorter than one physics step of dt = " + number(dt_f) +
                         " s: the robot would never move (the voxels are too large or too soft)");
  const double frames = control_rate * eval_seconds;
  if (!(frames >= 0.5))
    throw WorkLimitError("task.eval_seconds = " + number(eval_seconds) +
                         " s is shorter than half a control frame: no frame would be simulated");
  if (!(frames * work.steps_per_frame <= static_cast<double>(kMaxStepsPerEvaluation)))
    throw WorkLimitError(
        "task.eval_seconds = " + number(eval_seconds) + " s needs " + number(std::round(frames)) +
        " control frames of " + std::to_string(work.steps_per_frame) +
        " physics steps, more than the "
        "limit of " +
        std::to_string(kMaxStepsPerEvaluation) + " steps per evaluation (docs/model.md §5)");
  work.frames = static_cast<int>(std::lround(frames));
  return work;
}

float smallest_time_step(const PhysicsConfig& cfg,
                         const std::vector<StructuralMaterial>& materials) {
  float smallest = 0.0f;
  const int count = static_cast<int>(materials.size());
  BodyPlan plan;
  plan.materials = materials;
  plan.voxel_size = cfg.voxel_size;
  // A lone voxel (no link: §2.14's voxel formula) and each pair of neighbours (the link formula).
  for (int a = 1; a <= count; ++a) {
    for (int b = 0; b <= count; ++b) {
      plan.lattice = {b == 0 ? 1 : 2, 1, 1};
      plan.cells = b == 0 ? std::vector<int>{a} : std::vector<int>{a, b};
      const float dt = build_model(plan, cfg).dt_f;
      if (smallest == 0.0f || dt < smallest) smallest = dt;
    }
  }
  return smallest;
}

void check_run_work(const Config& config) {
  const PhysicsConfig& p = config.physics;
  const float dt = smallest_time_step(p, material_table(p));
  try {
    evaluation_work(dt, config.task.control_rate, config.task.eval_seconds);
  } catch (const WorkLimitError& e) {
    throw WorkLimitError("physics.voxel_size = " + number(p.voxel_size) +
                         " m, physics.youngs_modulus_max = " + number(p.youngs_modulus_max) +
                         " Pa, physics.youngs_modulus_min = " + number(p.youngs_modulus_min) +
                         " Pa, physics.density = " + number(p.density) +
                         " kg/m^3 and physics.dt_fraction = " + number(p.dt_fraction) +
                         " give a smallest time step of " + number(dt) + " s: " + e.what());
  }
}

}  // namespace softevo::physics
