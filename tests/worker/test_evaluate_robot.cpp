// Robot evaluation (worker/evaluate_robot, worker/simulation): the main loop of §5 on a small
// synthetic robot: step and frame counts, determinism, the first sensor reading, ablations,
// the trace observer, invalid bodies; and that the thesis champions' setup matches §13.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "tests/test_controller_spec.hpp"
#include "worker/evaluate_robot.hpp"

namespace fs = std::filesystem;
using namespace softevo;

namespace {

fs::path shared_dir() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  return (env ? fs::path(env) : fs::current_path()) / ".." / "shared";
}

// 6x4x4 block of material 10 with two chambers (cells 11 and 12) side by side.
BodyPlan two_chamber_block() {
  BodyPlan plan;
  plan.lattice = {7, 4, 4};
  plan.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) plan.materials.push_back({1.0e4 * k, 1000.0});
  plan.cells.assign(7 * 4 * 4, 10);
  for (int y = 1; y <= 2; ++y)
    for (int z = 1; z <= 2; ++z) {
      plan.cells[plan.cell_index(1, y, z)] = 11;
      plan.cells[plan.cell_index(2, y, z)] = 11;
      plan.cells[plan.cell_index(4, y, z)] = 12;
      plan.cells[plan.cell_index(5, y, z)] = 12;
    }
  return plan;
}

ControllerSpec controller(bool closed, bool directed) {
  return test::make_controller(
      closed, directed, [](int i) { return std::sin(2.0 + 1.3 * i); }, 3.0);
}

Config short_config(double seconds) {
  Config c;
  c.task.eval_seconds = seconds;
  return c;
}

}  // namespace

TEST(EvaluateRobot, CountsFramesStepsAndTime) {
  const Config cfg = short_config(0.5);
  int frames_seen = 0, steps_per_frame = 0, chambers = 0;
  EvalOptions opts;
  opts.on_start = [&](const worker::TraceHeader& h) {
    steps_per_frame = h.steps_per_frame;
    chambers = h.chambers;
    EXPECT_EQ(h.frames, 30);
  };
  opts.on_frame = [&](const worker::TraceFrame& f) {
    EXPECT_EQ(f.frame, frames_seen);
    EXPECT_EQ(f.pressures.size(), 2u);
    EXPECT_EQ(f.valve_commands.size(), 4u);
    ++frames_seen;
  };
  const EvalResult r = evaluate_robot(cfg, two_chamber_block(), controller(false, false), -1, opts);
  ASSERT_EQ(r.status, EvalStatus::ok) << r.message;
  EXPECT_EQ(chambers, 2);
  EXPECT_EQ(r.chambers, 2);
  EXPECT_EQ(r.voxels, 7 * 4 * 4 - 16);  // two 2x2x2 cavities
  // dt of a 100 kPa robot: 1.591549e-4 s -> floor((1/60)/dt) = 104 steps per frame (§2.14).
  EXPECT_EQ(steps_per_frame, 104);
  EXPECT_EQ(r.steps, 30 * 104);
  EXPECT_NEAR(r.sim_seconds, 30 * 104 * 1.5915494e-4, 1e-6 * r.sim_seconds);
  EXPECT_EQ(frames_seen, 31);  // one record per frame plus the final state
  ASSERT_EQ(r.components.size(), 1u);
  EXPECT_DOUBLE_EQ(r.fitness, r.components[0].fitness);
}

TEST(EvaluateRobot, RepeatableBitForBit) {
  const Config cfg = short_config(0.5);
  for (bool closed : {false, true}) {
    const EvalResult a = evaluate_robot(cfg, two_chamber_block(), controller(closed, true), 2);
    const EvalResult b = evaluate_robot(cfg, two_chamber_block(), controller(closed, true), 2);
    ASSERT_EQ(a.status, EvalStatus::ok);
    EXPECT_EQ(std::memcmp(&a.fitness, &b.fitness, sizeof(double)), 0)
        << a.fitness << " " << b.fitness;
    EXPECT_NE(a.fitness, 0.0);
  }
}

TEST(EvaluateRobot, FirstSensorReadingIsTheConfiguredPressure) {
  // Closed loop: the first frame reads pneumatics.initial_sensor_pressure for every chamber
  // (SPEC section 3). 0 bar (default) and 1 bar must drive the controller differently.
  Config c0 = short_config(0.5), c1 = short_config(0.5);
  c1.pneumatics.initial_sensor_pressure = 1.0e5;
  std::vector<float> first_inputs;
  EvalOptions opts;
  opts.on_frame = [&](const worker::TraceFrame& f) {
    if (f.frame == 0) first_inputs.assign(f.inputs.begin(), f.inputs.end());
  };
  const EvalResult a = evaluate_robot(c0, two_chamber_block(), controller(true, false), -1, opts);
  ASSERT_EQ(first_inputs.size(), 12u);
  EXPECT_FLOAT_EQ(first_inputs[2], -21.0f);  // (0 - 1) * 20 - 1
  EXPECT_FLOAT_EQ(first_inputs[3], -21.0f);
  EXPECT_FLOAT_EQ(first_inputs[4], 0.0f);  // zero padding for absent chambers
  const EvalResult b = evaluate_robot(c1, two_chamber_block(), controller(true, false), -1, opts);
  EXPECT_FLOAT_EQ(first_inputs[2], -1.0f);  // 1 bar
  EXPECT_NE(a.fitness, b.fitness);
}

TEST(EvaluateRobot, AblationsZeroTheirInputs) {
  const Config cfg = short_config(0.5);
  std::vector<std::vector<float>> inputs;
  auto record = [&](EvalOptions o) {
    inputs.clear();
    o.on_frame = [&](const worker::TraceFrame& f) {
      inputs.emplace_back(f.inputs.begin(), f.inputs.end());
    };
    return o;
  };
  EvalOptions osc;
  osc.ablate_oscillator = true;
  const EvalResult base =
      evaluate_robot(cfg, two_chamber_block(), controller(true, true), 0, record({}));
  const auto base_inputs = inputs;
  const EvalResult no_osc =
      evaluate_robot(cfg, two_chamber_block(), controller(true, true), 0, record(osc));
  for (const auto& in : inputs) {
    EXPECT_EQ(in[0], 0.0f);
    EXPECT_EQ(in[1], 0.0f);
  }
  EXPECT_NE(base_inputs[5][0], 0.0f);
  EXPECT_NE(no_osc.fitness, base.fitness);
  EvalOptions sens;
  sens.ablate_sensors = true;
  const EvalResult no_sens =
      evaluate_robot(cfg, two_chamber_block(), controller(true, true), 0, record(sens));
  for (const auto& in : inputs) {
    EXPECT_NE(in[0], 0.0f + 2.0f);  // oscillator still fed
    for (std::size_t c = 3; c < in.size(); ++c) EXPECT_EQ(in[c], 0.0f) << "input " << c;
  }
  EXPECT_NE(inputs[5][2], 0.0f);  // the direction sensor is not a pressure sensor
  EXPECT_NE(no_sens.fitness, base.fitness);
}

TEST(EvaluateRobot, BodyWithoutChamberIsInvalid) {
  BodyPlan plan = two_chamber_block();
  for (int& c : plan.cells) c = c >= 11 ? 0 : c;
  const EvalResult r = evaluate_robot(short_config(0.1), plan, controller(false, false), -1);
  EXPECT_EQ(r.status, EvalStatus::invalid_body);
  EXPECT_EQ(r.fitness, 0.0);
}

TEST(EvaluateRobot, BadControllerIsAFailureNotACrash) {
  ControllerSpec c = controller(false, false);
  c.vectors.weights_out.resize(3);
  const EvalResult r = evaluate_robot(short_config(0.1), two_chamber_block(), c, -1);
  EXPECT_EQ(r.status, EvalStatus::failed);
  EXPECT_NE(r.message.find("weights_out"), std::string::npos) << r.message;
}

TEST(EvaluateRobot, DirectedTaskRunsEveryDirection) {
  Config cfg = short_config(0.3);
  cfg.task.kind = "directed";
  const EvalResult r = evaluate_task(cfg, two_chamber_block(), controller(false, true));
  ASSERT_EQ(r.components.size(), 5u);
  double sum = 0.0;
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(r.components[i].direction_deg, cfg.task.directions[i]);
    sum += r.components[i].fitness;
  }
  if (r.status == EvalStatus::ok) {
    EXPECT_DOUBLE_EQ(r.fitness, sum);
  }
}

TEST(EvaluateRobot, ChampionTimeStepsMatchTheThesisSimulator) {
  // §13 acceptance test 3: dt and steps per frame per champion (`reference.dt`), without
  // simulating more than one frame.
  const fs::path dir = shared_dir() / "reference" / "bestbots";
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared/reference/bestbots not found (" << dir << ")";
  for (const char* name : {"gait-open-08", "gait-closed-03", "gait-closed-10"}) {
    const RobotFile robot = read_robot_file((dir / (std::string(name) + ".robot.json")).string());
    double dt = 0.0;
    EvalOptions opts;
    opts.on_start = [&](const worker::TraceHeader& h) { dt = h.model->dt; };
    Config cfg = short_config(1.0 / 60.0);
    const EvalResult r = evaluate_robot(cfg, robot.body, robot.controller, -1, opts);
    ASSERT_EQ(r.status, EvalStatus::ok) << name;
    const auto ref = robot.reference_json;
    const auto pos = ref.find("\"dt\":");
    ASSERT_NE(pos, std::string::npos);
    const double ref_dt = std::stod(ref.substr(pos + 5));
    EXPECT_NEAR(dt, ref_dt, 1e-6 * ref_dt) << name;  // reference prints 6 digits
    EXPECT_EQ(r.steps, static_cast<std::int64_t>(1.0f / 60.0f / static_cast<float>(dt))) << name;
  }
}
