// physics/work_limits.hpp: the schedule of docs/model.md §5 step 8 (the numbers the main loop
// always used), its limits, the smallest time step a config's materials allow, and the up-front
// check of a run's config that names the keys.
#include <gtest/gtest.h>

#include <string>

#include "common/config.hpp"
#include "physics/work_limits.hpp"

namespace softevo::physics {
namespace {

std::string error_of(float dt_f, double control_rate, double eval_seconds) {
  try {
    evaluation_work(dt_f, control_rate, eval_seconds);
  } catch (const WorkLimitError& e) {
    return e.what();
  }
  return "no error";
}

TEST(WorkLimits, TheThesisScheduleIsUnchanged) {
  // dt of material 10 (E = 100 kPa) at 1 cm (§2.14 table): 104 steps per 1/60 s frame.
  const EvaluationWork w = evaluation_work(1.591549e-4f, 60.0, 10.0);
  EXPECT_EQ(w.steps_per_frame, 104);
  EXPECT_EQ(w.frames, 600);
  EXPECT_EQ(w.steps(), 62400);
}

TEST(WorkLimits, BeyondTheLimitsOrNothingToSimulateIsAnError) {
  EXPECT_NE(error_of(1.6e-8f, 60.0, 10.0).find("more than the limit of 100000"), std::string::npos);
  EXPECT_NE(error_of(1.0e-30f, 60.0, 10.0).find("more than the limit of 100000"),
            std::string::npos);  // beyond int range: the conversion used to give 0 steps
  EXPECT_NE(error_of(0.0f, 60.0, 10.0).find("more than the limit"), std::string::npos);
  EXPECT_NE(error_of(0.1f, 60.0, 10.0).find("shorter than one physics step"), std::string::npos);
  EXPECT_NE(error_of(1.591549e-4f, 60.0, 0.001).find("no frame would be simulated"),
            std::string::npos);
  // 3600 s at dt_fraction 0.1: 216,000 frames of 1047 steps.
  EXPECT_NE(error_of(1.591549e-5f, 60.0, 3600.0).find("steps per evaluation"), std::string::npos);
  EXPECT_EQ(error_of(1.591549e-4f, 60.0, 3600.0), "no error");  // 22.5 M steps
}

TEST(WorkLimits, SmallestTimeStepIsTheStiffestMaterialsLink) {
  const Config c;
  EXPECT_NEAR(smallest_time_step(c.physics, material_table(c.physics)), 1.591549e-4, 1e-9);
}

TEST(WorkLimits, RunCheckNamesTheKeys) {
  EXPECT_NO_THROW(check_run_work(Config{}));
  Config tiny;
  tiny.physics.voxel_size = 1.0e-6;
  try {
    check_run_work(tiny);
    ADD_FAILURE() << "a 1e-6 m voxel passed";
  } catch (const WorkLimitError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("physics.voxel_size = 1e-06 m, physics.youngs_modulus_max = 100000 Pa", 0),
              0u)
        << m;
    EXPECT_NE(m.find("more than the limit of 100000"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace softevo::physics
