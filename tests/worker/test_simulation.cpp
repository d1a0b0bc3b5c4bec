// The stepping simulation (worker/simulation.hpp): driven frame by frame by the robot's own
// controller it gives evaluate()'s bits (gait, closed loop, the directed task's inputs); the
// frame and step counts, its refusals (ended simulation, wrong command count, bad unit) and an
// invalid body.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "common/config.hpp"
#include "physics/state.hpp"
#include "tasks/task.hpp"
#include "tests/test_controller_spec.hpp"
#include "tests/worker/two_chamber_block.hpp"
#include "worker/controller.hpp"
#include "worker/evaluate.hpp"
#include "worker/simulation.hpp"

using namespace softevo;

namespace {

ControllerSpec controller(bool closed, bool directed) {
  return test::make_controller(
      closed, directed, [](int i) { return std::cos(0.7 + 2.1 * i); }, 2.5);
}

Config config_of(TaskKind kind, double seconds) {
  Config c;
  c.task.kind = kind;
  c.task.eval_seconds = seconds;
  c.run.eval_timeout_seconds = 0.0;
  return c;
}

std::uint64_t bits(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Unit `unit` stepped by the robot's own controller, then scored as evaluate() scores it.
EvalResult stepped(const Config& config, const tasks::Task& task, const ControllerSpec& spec,
                   int unit, std::uint64_t* state_hash = nullptr) {
  worker::Simulation sim(config, task, test::two_chamber_block(), unit);
  worker::ElmanController brain(spec, config.task.control_rate);
  std::vector<float> task_inputs(static_cast<std::size_t>(task.controller_inputs()));
  std::vector<float> sensors(static_cast<std::size_t>(sim.chambers()));
  std::vector<float> commands(static_cast<std::size_t>(sim.valve_count()));
  while (sim.running()) {
    sim.task_inputs(task_inputs);
    for (int q = 0; q < sim.chambers(); ++q) sensors[q] = sim.sensor_pressure_bar(q);
    brain.act(task_inputs, sensors, commands);
    sim.step(commands);
  }
  if (state_hash) *state_hash = physics::state_hash(sim.state());
  EvalResult r = sim.finish();
  worker::finalize_unit_result(task, r);
  return r;
}

}  // namespace

TEST(Simulation, DrivenByTheOwnControllerGivesTheBitsOfEvaluate) {
  struct Case {
    TaskKind kind;
    bool closed;
    bool directed;
    int unit;
  };
  for (const Case c : {Case{TaskKind::gait, false, false, 0}, Case{TaskKind::gait, true, false, 0},
                       Case{TaskKind::directed, true, true, 1}}) {
    const Config cfg = config_of(c.kind, 0.5);
    const auto task = tasks::make_task(cfg);
    const ControllerSpec spec = controller(c.closed, c.directed);
    const EvalResult direct = worker::evaluate(cfg, *task, test::two_chamber_block(), spec, c.unit);
    const EvalResult by_steps = stepped(cfg, *task, spec, c.unit);
    ASSERT_EQ(direct.status, EvalStatus::ok) << direct.message;
    EXPECT_EQ(by_steps.status, direct.status);
    EXPECT_EQ(bits(by_steps.fitness), bits(direct.fitness)) << to_string(c.kind);
    EXPECT_EQ(by_steps.steps, direct.steps);
    ASSERT_EQ(by_steps.components.size(), 1u);
    ASSERT_EQ(direct.components.size(), 1u);
    EXPECT_EQ(by_steps.components[0].values, direct.components[0].values);
  }
}

TEST(Simulation, CountsFramesAndStepsAndRefusesToRunPastTheEnd) {
  const Config cfg = config_of(TaskKind::gait, 0.25);
  const auto task = tasks::make_task(cfg);
  worker::Simulation sim(cfg, *task, test::two_chamber_block(), 0);
  EXPECT_EQ(sim.frames(), 15);
  EXPECT_EQ(sim.chambers(), 2);
  EXPECT_EQ(sim.valve_count(), 4);
  EXPECT_GT(sim.steps_per_frame(), 0);
  const std::vector<float> wrong(3, 0.5f);
  EXPECT_THROW(sim.step(wrong), std::invalid_argument);
  const std::vector<float> open(4, 1.0f);
  while (sim.running()) ASSERT_EQ(sim.step(open), EvalStatus::ok);
  EXPECT_EQ(sim.frame(), 15);
  EXPECT_EQ(sim.steps(), 15LL * sim.steps_per_frame());
  EXPECT_GT(sim.time(), 0.2);
  EXPECT_THROW(sim.step(open), std::logic_error);
}

TEST(Simulation, SameCommandsSameState) {
  const Config cfg = config_of(TaskKind::gait, 0.25);
  const auto task = tasks::make_task(cfg);
  std::uint64_t first = 0, second = 0;
  stepped(cfg, *task, controller(false, false), 0, &first);
  stepped(cfg, *task, controller(false, false), 0, &second);
  EXPECT_EQ(first, second);
}

TEST(Simulation, RefusesAUnitOutsideTheTask) {
  const Config cfg = config_of(TaskKind::gait, 0.25);
  const auto task = tasks::make_task(cfg);
  EXPECT_THROW(worker::Simulation(cfg, *task, test::two_chamber_block(), 1), std::invalid_argument);
}

TEST(Simulation, ABodyWithoutChambersNeverRuns) {
  const Config cfg = config_of(TaskKind::gait, 0.25);
  const auto task = tasks::make_task(cfg);
  BodyPlan solid = test::two_chamber_block();
  for (int& v : solid.cells) v = v > 10 ? 10 : v;
  worker::Simulation sim(cfg, *task, solid, 0);
  EXPECT_EQ(sim.status(), EvalStatus::invalid_body);
  EXPECT_FALSE(sim.running());
  const EvalResult r = sim.finish();
  EXPECT_EQ(r.status, EvalStatus::invalid_body);
  EXPECT_EQ(r.steps, 0);
}

TEST(Simulation, StopEndsItWithTheGivenStatus) {
  const Config cfg = config_of(TaskKind::gait, 0.25);
  const auto task = tasks::make_task(cfg);
  worker::Simulation sim(cfg, *task, test::two_chamber_block(), 0);
  sim.stop(EvalStatus::timeout, "deadline");
  EXPECT_FALSE(sim.running());
  EvalResult r = sim.finish();
  worker::finalize_unit_result(*task, r);
  EXPECT_EQ(r.status, EvalStatus::timeout);
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_THROW(sim.stop(EvalStatus::ok, ""), std::invalid_argument);
}

// The ground of an evaluation is a function of the ids terrain.resample names, and of nothing
// else (docs/model.md §2.8a): the same on every rank and in replay.
TEST(Simulation, TerrainSeedFollowsTheResampleChoice) {
  Config config = parse_config("[terrain]\nkind = \"heightfield\"\n", "t");
  EXPECT_EQ(worker::terrain_params(Config{}, {3, 7}, 0).kind, physics::TerrainKind::flat);
  const auto seed = [&](const char* resample, std::int64_t generation, std::int64_t id, int unit) {
    config.terrain.resample = parse_choice<TerrainResample>(resample, "resample");
    const physics::TerrainParams p = worker::terrain_params(config, {generation, id}, unit);
    EXPECT_EQ(p.kind, physics::TerrainKind::bumps);
    EXPECT_EQ(p.shape.amplitude, config.terrain.shape.amplitude);
    return p.seed;
  };
  EXPECT_EQ(seed("per_run", 0, 0, 0), seed("per_run", 5, 9, 2));
  EXPECT_EQ(seed("per_generation", 4, 0, 0), seed("per_generation", 4, 9, 2));
  EXPECT_NE(seed("per_generation", 4, 0, 0), seed("per_generation", 5, 0, 0));
  EXPECT_EQ(seed("per_evaluation", 4, 9, 2), seed("per_evaluation", 4, 9, 2));
  EXPECT_NE(seed("per_evaluation", 4, 9, 2), seed("per_evaluation", 4, 8, 2));
  EXPECT_NE(seed("per_evaluation", 4, 9, 2), seed("per_evaluation", 4, 9, 1));
  const std::uint64_t run1 = seed("per_run", 0, 0, 0);
  config.run.seed = 2;
  EXPECT_NE(seed("per_run", 0, 0, 0), run1) << "another run, another ground";
  config.terrain.seed = 5;
  const std::uint64_t terrain5 = seed("per_run", 0, 0, 0);
  config.terrain.seed = 6;
  EXPECT_NE(seed("per_run", 0, 0, 0), terrain5);
}
