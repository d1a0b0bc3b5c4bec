// A thesis gait champion walking over 1 cm bumps (docs/model.md §2.8a, issue 19's validation): no
// voxel centre ever gets deeper than a stated tolerance below the local ground height, checked
// after every physics step, with both integrators. The test drives the evaluation's own pieces
// step by step (worker::Simulation advances whole frames) and checks that its loop gives the
// Simulation's final state bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "physics/model.hpp"
#include "physics/observables.hpp"
#include "physics/pneumatics.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "physics/terrain.hpp"
#include "physics/work_limits.hpp"
#include "tasks/task.hpp"
#include "tests/reference_data.hpp"
#include "worker/controller.hpp"
#include "worker/simulation.hpp"

using namespace softevo;

namespace {

constexpr double kSeconds = 3.0;  // [s]

Config rough_config(const RobotFile& robot, const std::string& integrator) {
  Config c;
  c.run.eval_timeout_seconds = 0.0;
  c.task.eval_seconds = kSeconds;
  c.task.control = robot.controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
  c.physics.integrator = parse_choice<Integrator>(integrator, "integrator");
  c.terrain.kind = GroundKind::heightfield;
  c.terrain.heightfield = HeightfieldKind::bumps;
  c.terrain.shape.amplitude = 0.01;  // 1 cm [m]
  c.terrain.shape.correlation_length = 0.05;
  c.terrain.seed = 4;
  return c;
}

struct Walk {
  double deepest = -1.0;   // largest (ground height - centre z) over every voxel and step [m]
  double travelled = 0.0;  // centre of mass x, end minus start [m]
  double voxel_size = 0.0;
  std::uint64_t state_hash = 0;
};

// The frame loop of §5 with a check after every physics step.
Walk walk(const Config& config, const RobotFile& robot) {
  physics::BuildOptions options;
  options.terrain = worker::terrain_params(config, {}, 0);
  const physics::Model model = physics::build_model(robot.body, config.physics, options);
  physics::State state = physics::initial_state(model);
  physics::Scratch scratch = physics::make_scratch(model);
  const physics::PneumaticsModel pm =
      physics::build_pneumatics(robot.body, model, config.pneumatics);
  physics::PneumaticsState ps = physics::initial_pneumatics_state(pm, state.pos);
  physics::PneumaticsScratch pscratch = physics::make_pneumatics_scratch(pm);
  std::vector<physics::Vec3> force(static_cast<std::size_t>(model.voxel_count),
                                   physics::Vec3::Zero());
  const physics::EvaluationWork work =
      physics::evaluation_work(model.dt_f, config.task.control_rate, kSeconds);
  worker::ElmanController brain(robot.controller, config.task.control_rate);
  std::vector<float> sensors(static_cast<std::size_t>(pm.chamber_count));
  std::vector<float> commands(static_cast<std::size_t>(pm.valve_count));
  Walk w;
  w.voxel_size = model.voxel_size;
  const double start_x = physics::centre_of_mass(model, state).x();
  for (int frame = 0; frame < work.frames; ++frame) {
    for (int q = 0; q < pm.chamber_count; ++q)  // §3.7: frame 0 reads the configured value
      sensors[q] = frame == 0 ? static_cast<float>(config.pneumatics.initial_sensor_pressure /
                                                   physics::kPascalPerBar)
                              : ps.pressure[q];
    brain.act({}, sensors, commands);
    physics::set_valve_commands(ps, commands);
    if (physics::flipped(model, state) || physics::exploded(model, state)) break;
    for (int s = 0; s < work.steps_per_frame; ++s) {
      physics::pneumatics_update(pm, ps, pscratch, state.pos, force);
      EXPECT_EQ(physics::step(model, state, scratch, force), physics::StepStatus::ok);
      for (const physics::Vec3& p : state.pos)
        w.deepest =
            std::max(w.deepest, physics::terrain_height(model.terrain, p.x(), p.y()) - p.z());
    }
  }
  w.travelled = physics::centre_of_mass(model, state).x() - start_x;
  w.state_hash = physics::state_hash(state);
  return w;
}

std::uint64_t simulation_state_hash(const Config& config, const RobotFile& robot) {
  const auto task = tasks::make_task(config);
  worker::Simulation sim(config, *task, robot.body, 0);
  worker::ElmanController brain(robot.controller, config.task.control_rate);
  std::vector<float> sensors(static_cast<std::size_t>(sim.chambers()));
  std::vector<float> commands(static_cast<std::size_t>(sim.valve_count()));
  while (sim.running()) {
    for (int q = 0; q < sim.chambers(); ++q) sensors[q] = sim.sensor_pressure_bar(q);
    brain.act({}, sensors, commands);
    sim.step(commands);
  }
  return physics::state_hash(sim.state());
}

}  // namespace

TEST(RoughWalk, GaitChampionOnOneCentimetreBumpsNeverSinksIntoTheGround) {
  // gait-open-01: the best open-loop gait (109 cm in 10 s on flat ground).
  const auto path = softevo::test::reference_bestbots() / "gait-open-01.robot.json";
  if (!std::filesystem::exists(path))
    GTEST_SKIP() << "thesis champion not found at " << path << " (../shared/reference)";
  const RobotFile robot = read_robot_file(path.string());
  for (const char* integrator : {"pneuvox", "symplectic"}) {
    const Config config = rough_config(robot, integrator);
    const Walk w = walk(config, robot);
    // Tolerance: a quarter voxel (2.5 mm). The contact is a penalty spring (§2.8): a centre
    // sinks by its load over the penetration stiffness, more in the impacts of a gait, and the
    // depth is measured vertically, which under a slanted bump is more than along the normal.
    // Measured: 1.46 mm (pneuvox) and 1.22 mm (symplectic), against 1.16 mm and 0.66 mm for the
    // same gait on flat ground; a centre that fell through a bump would sink by up to the 1 cm
    // amplitude.
    std::printf(
        "[%s] %.1f s on 1 cm bumps: travelled %.3f m, deepest centre %.3e m below "
        "the local ground\n",
        integrator, kSeconds, w.travelled, w.deepest);
    EXPECT_LT(w.deepest, 0.25 * w.voxel_size) << integrator;
    EXPECT_GT(w.travelled, 0.1) << integrator << ": it must walk over several bumps";
    if (std::string(integrator) == "pneuvox") {
      EXPECT_EQ(w.state_hash, simulation_state_hash(config, robot))
          << "the test's loop is not the evaluation's";
    }
  }
}
