// evaluate_unit (worker/evaluate_unit.hpp): the MPI-free work unit. Failures are statuses with
// messages, never exceptions; only a config-hash mismatch throws.
#include "worker/evaluate_unit.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

#include "common/rng.hpp"
#include "evo/population.hpp"

namespace softevo::worker {
namespace {

Config tiny_config() {
  Config c;
  c.body.lattice = {5, 5, 5};
  c.task.eval_seconds = 0.1;
  c.neat.pop_size = 4;
  return c;
}

// A viable genome of the population of `config` (random immigrants make every member viable).
EvalRequest request_for(const Config& config, std::int32_t direction = -1) {
  const evo::Population pop = evo::Population::create(config, 11);
  EvalRequest r;
  r.config_hash = config_hash(config);
  r.generation = 0;
  r.genome_id = pop.members().front().id;
  r.direction_index = direction;
  r.genome = evo::encode_genome(pop.members().front().genome);
  return r;
}

TEST(EvaluateUnit, EvaluatesARealRobotDeterministically) {
  const Config c = tiny_config();
  const EvalRequest req = request_for(c);
  const EvalResult a = evaluate_unit(c, config_hash(c), req);
  const EvalResult b = evaluate_unit(c, config_hash(c), req);
  EXPECT_EQ(a.genome_id, req.genome_id);
  EXPECT_EQ(a.direction_index, -1);
  EXPECT_TRUE(a.status == EvalStatus::ok || is_killed(a.status)) << a.message;
  EXPECT_NE(a.status, EvalStatus::failed) << a.message;
  EXPECT_GT(a.voxels, 0);
  EXPECT_EQ(a.fitness, b.fitness);  // bit-identical
  EXPECT_EQ(a.status, b.status);
}

TEST(EvaluateUnit, ConfigHashMismatchThrows) {
  const Config c = tiny_config();
  EvalRequest req = request_for(c);
  req.config_hash ^= 1;
  EXPECT_THROW(evaluate_unit(c, config_hash(c), req), ConfigMismatch);
}

TEST(EvaluateUnit, GarbageGenomeIsAFailedResult) {
  const Config c = tiny_config();
  EvalRequest req = request_for(c);
  req.genome.resize(req.genome.size() / 2);  // truncated
  const EvalResult r = evaluate_unit(c, config_hash(c), req);
  EXPECT_EQ(r.status, EvalStatus::failed);
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_FALSE(r.message.empty());
}

TEST(EvaluateUnit, TestHookMakesOneGenomeFail) {
  const Config c = tiny_config();
  const EvalRequest req = request_for(c);
  setenv("SOFTEVO_TEST_FAIL_GENOME", std::to_string(req.genome_id).c_str(), 1);
  const EvalResult r = evaluate_unit(c, config_hash(c), req);
  setenv("SOFTEVO_TEST_FAIL_GENOME", std::to_string(req.genome_id + 1000).c_str(), 1);
  const EvalResult other = evaluate_unit(c, config_hash(c), req);
  unsetenv("SOFTEVO_TEST_FAIL_GENOME");
  EXPECT_EQ(r.status, EvalStatus::failed);
  EXPECT_NE(r.message.find("SOFTEVO_TEST_FAIL_GENOME"), std::string::npos) << r.message;
  EXPECT_NE(other.status, EvalStatus::failed);
}

TEST(EvaluateUnit, TimeoutIsAStatus) {
  Config c = tiny_config();
  c.task.eval_seconds = 5.0;            // far more than the budget below
  c.run.eval_timeout_seconds = 1.0e-6;  // [s]: spent before the first control frame ends
  const EvalRequest req = request_for(c);
  const EvalResult r = evaluate_unit(c, config_hash(c), req);
  EXPECT_EQ(r.status, EvalStatus::timeout) << r.message;
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_NE(r.message.find("eval_timeout_seconds"), std::string::npos);
  EXPECT_LT(r.wall_seconds, 2.0);  // stopped early, not after 5 s of simulation
}

TEST(EvaluateUnit, StandInSimulatorAndDirections) {
  const Config c = tiny_config();
  UnitOptions o;
  o.simulate = [](const Config&, const BuiltRobot& robot, const EvalRequest& req) {
    EvalResult r;
    r.fitness = 10.0 + req.direction_index;
    r.voxels = static_cast<std::int32_t>(robot.body.cells.size());
    return r;
  };
  const EvalResult r = evaluate_unit(c, config_hash(c), request_for(c, 3), o);
  EXPECT_EQ(r.direction_index, 3);
  EXPECT_EQ(r.fitness, 13.0);
}

TEST(EvaluateUnit, BuildRobotFillsMaterialsFromTheConfig) {
  const Config c = tiny_config();
  const evo::Population pop = evo::Population::create(c, 5);
  const BuiltRobot r = build_robot(c, pop.members().front().genome);
  EXPECT_TRUE(r.valid);
  EXPECT_TRUE(r.actuatable);
  ASSERT_EQ(r.body.materials.size(), static_cast<std::size_t>(c.physics.material_count));
  EXPECT_EQ(r.body.materials.front().youngs_modulus, c.physics.youngs_modulus_min);
  EXPECT_EQ(r.body.materials.back().youngs_modulus, c.physics.youngs_modulus_max);
  EXPECT_EQ(r.body.voxel_size, c.physics.voxel_size);
}

}  // namespace
}  // namespace softevo::worker
