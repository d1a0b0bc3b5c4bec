// The batched step (physics/batch.hpp): every lane equals its evaluation stepped alone by
// physics::step(), bit for bit, at every SIMD width and batch size, with lanes that end at
// different steps (killed, diverged, non-finite), and bad input is refused. The 20 gait champions
// and dir-open-09 at every size: test_batch_champions.cpp (label long).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "physics/batch.hpp"
#include "physics/scenes.hpp"
#include "tests/physics/batch_lanes.hpp"
#include "tests/reference_data.hpp"

namespace fs = std::filesystem;
using namespace softevo;

namespace {

std::vector<physics::Simd> widths() {
  std::vector<physics::Simd> out;
  for (physics::Simd s : physics::simd_widths())
    if (physics::simd_supported(s)) out.push_back(s);
  return out;
}

// A 4x4x3 block dropped from rest (self-collision on), its states every 15 steps.
test::BatchCase block_case(int lanes, Integrator integrator = Integrator::pneuvox) {
  PhysicsConfig cfg;
  cfg.integrator = integrator;
  test::BatchCase c;
  c.model = physics::build_model(physics::solid_block(4, 4, 3, 1.0e5), cfg);
  physics::State s = physics::initial_state(c.model);
  physics::Scratch sc = physics::make_scratch(c.model);
  for (int k = 0; k < lanes; ++k) {
    c.states.push_back(s);
    for (int i = 0; i < 15; ++i) physics::step(c.model, s, sc);
  }
  return c;
}

TEST(Batch, EveryLaneOfABlockEqualsItsStepsAloneAtEveryWidthAndSize) {
  const test::BatchCase c = block_case(physics::kMaxBatchLanes);
  for (physics::Simd simd : widths())
    for (int lanes : {1, 2, 3, 5, 8, 9, 16})
      test::expect_lanes_equal_steps_alone(
          c.model, std::vector<physics::State>(c.states.begin(), c.states.begin() + lanes), simd,
          40, {}, "block");
}

TEST(Batch, LanesEndAtDifferentSteps) {
  test::BatchCase c = block_case(5);
  c.states[1].pos[0].x() += 2.0;  // strain > 100: diverges at its first step
  c.states[3].lin_mom[5].z() = std::numeric_limits<double>::quiet_NaN();  // non-finite
  // lane 2 is killed after 7 steps; lanes 0 and 4 run to the end
  for (physics::Simd simd : widths())
    test::expect_lanes_equal_steps_alone(c.model, c.states, simd, 20, {20, 20, 7, 20, 20},
                                         "ending lanes");
}

TEST(Batch, ABatchWhoseLanesAllEndedDoesNothing) {
  const test::BatchCase c = block_case(3);
  physics::BatchState batch = physics::make_batch_state(c.model, c.states);
  physics::BatchScratch scratch = physics::make_batch_scratch(c.model, batch);
  for (int k = 0; k < 3; ++k) physics::end_lane(batch, k);
  std::vector<physics::StepStatus> status(3, physics::StepStatus::diverged);
  physics::step_batch(c.model, batch, scratch, {}, status);
  physics::State out;
  for (int k = 0; k < 3; ++k) {
    EXPECT_FALSE(physics::lane_running(batch, k));
    EXPECT_EQ(status[k], physics::StepStatus::ok);
    physics::get_lane(batch, k, out);
    EXPECT_EQ(physics::state_hash(out), physics::state_hash(c.states[k])) << "lane " << k;
  }
}

TEST(Batch, ASymplecticModelStepsEachLaneAlone) {
  const test::BatchCase c = block_case(3, Integrator::symplectic);
  for (physics::Simd simd : widths())
    test::expect_lanes_equal_steps_alone(c.model, c.states, simd, 20, {}, "symplectic");
}

TEST(Batch, BadInputIsRefusedWithItsReason) {
  const test::BatchCase c = block_case(2);
  auto message_of = [](auto&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message_of([&] { physics::make_batch_state(c.model, {}); }).find("0 states"),
            std::string::npos);
  const std::vector<physics::State> many(physics::kMaxBatchLanes + 1, c.states[0]);
  EXPECT_NE(message_of([&] { physics::make_batch_state(c.model, many); }).find("1 to 16"),
            std::string::npos);
  const test::BatchCase other = block_case(1);
  physics::Model smaller = physics::build_model(physics::solid_block(2, 2, 2, 1.0e5), {});
  EXPECT_NE(message_of([&] { physics::make_batch_state(smaller, c.states); }).find("voxels"),
            std::string::npos);
  physics::BatchState batch = physics::make_batch_state(c.model, c.states);
  physics::BatchScratch scratch = physics::make_batch_scratch(c.model, batch);
  std::vector<physics::StepStatus> status(2);
  const std::vector<physics::Vec3> short_force(3, physics::Vec3::Zero());
  const std::vector<std::span<const physics::Vec3>> one{short_force};
  EXPECT_NE(message_of([&] {
              physics::step_batch(c.model, batch, scratch, one, status);
            }).find("external forces"),
            std::string::npos);
  const std::vector<std::span<const physics::Vec3>> two{short_force, short_force};
  EXPECT_NE(message_of([&] {
              physics::step_batch(c.model, batch, scratch, two, status);
            }).find("3 entries"),
            std::string::npos);
  std::vector<physics::StepStatus> three(3);
  EXPECT_NE(message_of([&] {
              physics::step_batch(c.model, batch, scratch, {}, three);
            }).find("3 statuses"),
            std::string::npos);
}

TEST(Batch, EveryLaneOfGaitOpen01AndDirOpen09EqualsItsEvaluationAlone) {
  const fs::path dir = test::reference_bestbots();
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared not found (" << dir << ")";
  for (const char* robot : {"gait-open-01", "dir-open-09"}) {
    const test::BatchCase c =
        test::batch_case_of_robot(dir / (std::string(robot) + ".robot.json"), 8);
    ASSERT_EQ(c.states.size(), 8u) << robot;
    for (physics::Simd simd : widths())
      for (int lanes : {5, 8})
        test::expect_lanes_equal_steps_alone(
            c.model, std::vector<physics::State>(c.states.begin(), c.states.begin() + lanes), simd,
            20, {}, robot);
  }
}

}  // namespace
