// The evaluation entry (worker/evaluate.hpp): the main loop of §5 on a small synthetic robot
// (step and frame counts, determinism, the first sensor reading, ablations, the trace observer,
// invalid bodies, every unit of a task, the thesis champions' setup of §9.8), and work units
// from requests (genome decoding, config hash, deadline, injected faults). Failures are statuses
// with messages, never exceptions; only a config-hash mismatch throws.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "evo/population.hpp"
#include "tasks/task.hpp"
#include "tests/test_controller_spec.hpp"
#include "tests/worker/two_chamber_block.hpp"
#include "worker/evaluate.hpp"

namespace fs = std::filesystem;
using namespace softevo;

namespace {

fs::path shared_dir() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  return (env ? fs::path(env) : fs::current_path()) / ".." / "shared";
}

using test::two_chamber_block;

ControllerSpec controller(bool closed, bool directed) {
  return test::make_controller(
      closed, directed, [](int i) { return std::sin(2.0 + 1.3 * i); }, 3.0);
}

Config short_config(double seconds, TaskKind kind = TaskKind::gait) {
  Config c;
  c.task.kind = kind;
  c.task.eval_seconds = seconds;
  return c;
}

// Work unit `unit` of the task of `config`.
EvalResult evaluate_robot(const Config& config, const BodyPlan& body,
                          const ControllerSpec& controller, int unit,
                          const worker::EvaluateOptions& options = {}) {
  const auto task = tasks::make_task(config);
  return worker::evaluate(config, *task, body, controller, unit, options);
}

}  // namespace

TEST(Evaluate, CountsFramesStepsAndTime) {
  const Config cfg = short_config(0.5);
  int frames_seen = 0, steps_per_frame = 0, chambers = 0;
  worker::EvaluateOptions opts;
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
  const EvalResult r = evaluate_robot(cfg, two_chamber_block(), controller(false, false), 0, opts);
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

TEST(Evaluate, RepeatableBitForBit) {
  const Config cfg = short_config(0.5, TaskKind::directed);
  for (bool closed : {false, true}) {
    const EvalResult a = evaluate_robot(cfg, two_chamber_block(), controller(closed, true), 2);
    const EvalResult b = evaluate_robot(cfg, two_chamber_block(), controller(closed, true), 2);
    ASSERT_EQ(a.status, EvalStatus::ok);
    EXPECT_EQ(std::memcmp(&a.fitness, &b.fitness, sizeof(double)), 0)
        << a.fitness << " " << b.fitness;
    EXPECT_NE(a.fitness, 0.0);
  }
}

TEST(Evaluate, FirstSensorReadingIsTheConfiguredPressure) {
  // Closed loop: the first frame reads pneumatics.initial_sensor_pressure for every chamber
  // (§3.7). 0 bar (default) and 1 bar must drive the controller differently.
  Config c0 = short_config(0.5), c1 = short_config(0.5);
  c1.pneumatics.initial_sensor_pressure = 1.0e5;
  std::vector<float> first_inputs;
  worker::EvaluateOptions opts;
  opts.on_frame = [&](const worker::TraceFrame& f) {
    if (f.frame == 0) first_inputs.assign(f.inputs.begin(), f.inputs.end());
  };
  const EvalResult a = evaluate_robot(c0, two_chamber_block(), controller(true, false), 0, opts);
  ASSERT_EQ(first_inputs.size(), 12u);
  EXPECT_FLOAT_EQ(first_inputs[2], -21.0f);  // (0 - 1) * 20 - 1
  EXPECT_FLOAT_EQ(first_inputs[3], -21.0f);
  EXPECT_FLOAT_EQ(first_inputs[4], 0.0f);  // zero padding for absent chambers
  const EvalResult b = evaluate_robot(c1, two_chamber_block(), controller(true, false), 0, opts);
  EXPECT_FLOAT_EQ(first_inputs[2], -1.0f);  // 1 bar
  EXPECT_NE(a.fitness, b.fitness);
}

TEST(Evaluate, AblationsZeroTheirInputs) {
  const Config cfg = short_config(0.5, TaskKind::directed);
  std::vector<std::vector<float>> inputs;
  auto record = [&](worker::EvaluateOptions o) {
    inputs.clear();
    o.on_frame = [&](const worker::TraceFrame& f) {
      inputs.emplace_back(f.inputs.begin(), f.inputs.end());
    };
    return o;
  };
  worker::EvaluateOptions osc;
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
  worker::EvaluateOptions sens;
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

TEST(Evaluate, TaskInputsTheControllerLacksOrTheTaskLacks) {
  // A directed controller on the gait task reads 0 for its direction input; the directed
  // task's direction sensor is not fed to a controller without that input.
  std::vector<float> first;
  worker::EvaluateOptions opts;
  opts.on_frame = [&](const worker::TraceFrame& f) {
    if (f.frame == 5) first.assign(f.inputs.begin(), f.inputs.end());
  };
  const ControllerSpec directed = controller(false, true);
  EXPECT_EQ(evaluate_robot(short_config(0.2), two_chamber_block(), directed, 0, opts).status,
            EvalStatus::ok);
  ASSERT_EQ(first.size(), 3u);
  EXPECT_EQ(first[2], 0.0f);
  evaluate_robot(short_config(0.2, TaskKind::directed), two_chamber_block(), directed, 3, opts);
  EXPECT_NE(first[2], 0.0f);  // towards +20 deg
  const EvalResult blind = evaluate_robot(short_config(0.2, TaskKind::directed),
                                          two_chamber_block(), controller(false, false), 3, opts);
  EXPECT_EQ(blind.status, EvalStatus::ok);
  EXPECT_EQ(first.size(), 2u);
}

TEST(Evaluate, BodyWithoutChamberIsInvalid) {
  BodyPlan plan = two_chamber_block();
  for (int& c : plan.cells) c = c >= 11 ? 0 : c;
  const EvalResult r = evaluate_robot(short_config(0.1), plan, controller(false, false), 0);
  EXPECT_EQ(r.status, EvalStatus::invalid_body);
  EXPECT_EQ(r.fitness, 0.0);
}

// A model without voxels has no time step: the pneumatics used to refuse it with "model dt must
// be > 0", hiding the real cause.
TEST(Evaluate, EmptyAndChamberOnlyBodiesNameTheCause) {
  BodyPlan empty = two_chamber_block();
  std::fill(empty.cells.begin(), empty.cells.end(), 0);
  const EvalResult e = evaluate_robot(short_config(0.1), empty, controller(false, false), 0);
  EXPECT_EQ(e.status, EvalStatus::invalid_body);
  EXPECT_EQ(e.message, "body has no cells (every cell is empty)");
  BodyPlan chambers_only = two_chamber_block();
  for (int& c : chambers_only.cells) c = c >= 11 ? c : 0;
  const EvalResult c =
      evaluate_robot(short_config(0.1), chambers_only, controller(false, false), 0);
  EXPECT_EQ(c.status, EvalStatus::invalid_body);
  EXPECT_EQ(c.message, "body has only chamber cells, no structural voxel (material 1..10)");
}

// physics/work_limits.hpp: an evaluation beyond the step limits, or one that would simulate
// nothing, is status failed before its first step. Before the limits, a voxel of 5e-6 m ran
// about 200,000 steps per control frame, and one of 1e-12 m (beyond int range) or of 10 m (a
// time step longer than a frame) reported status ok after 0 steps.
TEST(Evaluate, WorkBeyondTheLimitsIsAFailedStatusBeforeAnyStep) {
  BodyPlan small;  // two voxels of material 10 around a one-cell chamber
  small.lattice = {3, 1, 1};
  for (int k = 1; k <= 10; ++k) small.materials.push_back({1.0e4 * k, 1000.0});
  small.cells = {10, 11, 10};
  auto run = [&](double voxel_size, double seconds) {
    BodyPlan plan = small;
    plan.voxel_size = voxel_size;
    return evaluate_robot(short_config(seconds), plan, controller(false, false), 0);
  };
  for (const double voxel_size : {5.0e-6, 1.0e-12}) {
    const EvalResult r = run(voxel_size, 1.0 / 60.0);
    EXPECT_EQ(r.status, EvalStatus::failed) << voxel_size;
    EXPECT_EQ(r.steps, 0) << voxel_size;
    EXPECT_NE(r.message.find("more than the limit of 100000"), std::string::npos) << r.message;
  }
  const EvalResult huge = run(10.0, 1.0);
  EXPECT_EQ(huge.status, EvalStatus::failed);
  EXPECT_NE(huge.message.find("shorter than one physics step"), std::string::npos) << huge.message;
  const EvalResult no_frame = run(0.01, 0.001);
  EXPECT_EQ(no_frame.status, EvalStatus::failed);
  EXPECT_NE(no_frame.message.find("no frame would be simulated"), std::string::npos)
      << no_frame.message;
  EXPECT_EQ(run(0.01, 1.0 / 60.0).status, EvalStatus::ok);  // the thesis scale: 104 steps
}

TEST(Evaluate, BadControllerIsAFailureNotACrash) {
  ControllerSpec c = controller(false, false);
  c.vectors.weights_out.resize(3);
  const EvalResult r = evaluate_robot(short_config(0.1), two_chamber_block(), c, 0);
  EXPECT_EQ(r.status, EvalStatus::failed);
  EXPECT_NE(r.message.find("weights_out"), std::string::npos) << r.message;
}

TEST(Evaluate, EveryUnitOfTheTask) {
  const Config cfg = short_config(0.3, TaskKind::directed);
  const auto task = tasks::make_task(cfg);
  const EvalResult r =
      worker::evaluate_all_units(cfg, *task, two_chamber_block(), controller(false, true));
  ASSERT_EQ(r.components.size(), 5u);
  double sum = 0.0;
  for (std::size_t i = 0; i < 5; ++i) {
    if (r.components[i].status == EvalStatus::ok) {
      EXPECT_EQ(r.components[i].values[0], cfg.task.directions[i]);  // direction_deg
    }
    sum += r.components[i].fitness;
  }
  if (r.status == EvalStatus::ok) {
    EXPECT_DOUBLE_EQ(r.fitness, sum);
  }
}

TEST(Evaluate, ChampionTimeStepsMatchTheThesisSimulator) {
  // §9.8: dt and steps per frame per champion (`reference.dt`), without
  // simulating more than one frame.
  const fs::path dir = shared_dir() / "reference" / "bestbots";
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared/reference/bestbots not found (" << dir << ")";
  for (const char* name : {"gait-open-08", "gait-closed-03", "gait-closed-10"}) {
    const RobotFile robot = read_robot_file((dir / (std::string(name) + ".robot.json")).string());
    double dt = 0.0;
    worker::EvaluateOptions opts;
    opts.on_start = [&](const worker::TraceHeader& h) { dt = h.model->dt; };
    Config cfg = short_config(1.0 / 60.0);
    const EvalResult r = evaluate_robot(cfg, robot.body, robot.controller, 0, opts);
    ASSERT_EQ(r.status, EvalStatus::ok) << name;
    const auto ref = robot.reference_json;
    const auto pos = ref.find("\"dt\":");
    ASSERT_NE(pos, std::string::npos);
    const double ref_dt = std::stod(ref.substr(pos + 5));
    EXPECT_NEAR(dt, ref_dt, 1e-6 * ref_dt) << name;  // reference prints 6 digits
    EXPECT_EQ(r.steps, static_cast<std::int64_t>(1.0f / 60.0f / static_cast<float>(dt))) << name;
  }
}

namespace {

Config tiny_config() {
  Config c;
  c.body.lattice = {5, 5, 5};
  c.task.eval_seconds = 0.1;
  c.neat.pop_size = 4;
  return c;
}

// A work unit from a request, as a worker rank evaluates it.
EvalResult evaluate_request(const Config& config, const EvalRequest& request,
                            const worker::EvaluateOptions& options = {}) {
  const auto task = tasks::make_task(config);
  return worker::evaluate(config, *task, config_hash(config), request, options);
}

// A viable genome of the population of `config` (random immigrants make every member viable).
EvalRequest request_for(const Config& config, std::int32_t unit = 0) {
  const evo::Population pop =
      evo::Population::create(config, tasks::make_task(config)->controller_inputs(), 11);
  EvalRequest r;
  r.config_hash = config_hash(config);
  r.generation = 0;
  r.genome_id = pop.members().front().id;
  r.unit = unit;
  r.genome = evo::encode_genome(pop.members().front().genome);
  return r;
}

TEST(EvaluateRequest, EvaluatesARealRobotDeterministically) {
  const Config c = tiny_config();
  const EvalRequest req = request_for(c);
  const EvalResult a = evaluate_request(c, req);
  const EvalResult b = evaluate_request(c, req);
  EXPECT_EQ(a.genome_id, req.genome_id);
  EXPECT_EQ(a.unit, 0);
  EXPECT_TRUE(a.status == EvalStatus::ok || is_killed(a.status)) << a.message;
  EXPECT_NE(a.status, EvalStatus::failed) << a.message;
  EXPECT_GT(a.voxels, 0);
  EXPECT_EQ(a.fitness, b.fitness);  // bit-identical
  EXPECT_EQ(a.status, b.status);
}

TEST(EvaluateRequest, ConfigHashMismatchThrows) {
  const Config c = tiny_config();
  EvalRequest req = request_for(c);
  req.config_hash ^= 1;
  EXPECT_THROW(evaluate_request(c, req), worker::ConfigMismatch);
}

TEST(EvaluateRequest, GarbageGenomeIsAFailedResult) {
  const Config c = tiny_config();
  EvalRequest req = request_for(c);
  req.genome.resize(req.genome.size() / 2);  // truncated
  const EvalResult r = evaluate_request(c, req);
  EXPECT_EQ(r.status, EvalStatus::failed);
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_FALSE(r.message.empty());
}

TEST(EvaluateRequest, AnInjectedFaultIsAFailedResult) {
  const Config c = tiny_config();
  const EvalRequest req = request_for(c);
  worker::EvaluateOptions o;
  o.evaluate_robot = [&](const Config&, const tasks::Task&, const worker::BuiltRobot&,
                         const EvalRequest& r, const worker::EvaluateOptions&) {
    EvalResult failed;
    failed.status = EvalStatus::failed;
    failed.fitness = 12.0;  // a stand-in's fitness of a failed unit never counts
    failed.message = "injected fault of genome " + std::to_string(r.genome_id);
    return failed;
  };
  const EvalResult r = evaluate_request(c, req, o);
  EXPECT_EQ(r.status, EvalStatus::failed);
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_NE(r.message.find("injected fault"), std::string::npos) << r.message;
}

TEST(EvaluateRequest, AnExplicitDeadlineStopsTheUnit) {
  Config c = tiny_config();
  c.task.eval_seconds = 5.0;
  c.run.eval_timeout_seconds = 0.0;  // no limit from the config
  worker::EvaluateOptions o;
  o.deadline = worker::Clock::now();  // already passed
  const EvalResult r = evaluate_request(c, request_for(c), o);
  EXPECT_EQ(r.status, EvalStatus::timeout) << r.message;
  EXPECT_LT(r.wall_seconds, 2.0);
}

TEST(EvaluateRequest, TimeoutIsAStatus) {
  Config c = tiny_config();
  c.task.eval_seconds = 5.0;            // far more than the budget below
  c.run.eval_timeout_seconds = 1.0e-6;  // [s]: spent before the first control frame ends
  const EvalRequest req = request_for(c);
  const EvalResult r = evaluate_request(c, req);
  EXPECT_EQ(r.status, EvalStatus::timeout) << r.message;
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_NE(r.message.find("eval_timeout_seconds"), std::string::npos);
  EXPECT_LT(r.wall_seconds, 2.0);  // stopped early, not after 5 s of simulation
}

// A timeout beyond the clock's range saturates instead of wrapping into the past: 1e10 s made
// every evaluation "time out" at once (issue 39; the config now refuses it, the Python and
// command-line paths call deadline_after with what they are given).
TEST(EvaluateRequest, AHugeTimeoutNeverExpires) {
  for (double seconds : {1.0e10, 1.0e300, std::numeric_limits<double>::infinity()}) {
    const auto deadline = worker::deadline_after(seconds);
    ASSERT_TRUE(deadline.has_value());
    EXPECT_GT(*deadline, worker::Clock::now() + std::chrono::hours(24 * 365 * 100)) << seconds;
  }
  EXPECT_FALSE(worker::deadline_after(0.0).has_value());
  EXPECT_FALSE(worker::deadline_after(std::nan("")).has_value());
  Config c = tiny_config();
  c.task.eval_seconds = 0.05;
  worker::EvaluateOptions o;
  o.deadline = worker::deadline_after(1.0e10);
  const EvalResult r = evaluate_request(c, request_for(c), o);
  EXPECT_EQ(r.status, EvalStatus::ok) << r.message;
}

TEST(EvaluateRequest, StandInEvaluationAndUnits) {
  Config c = tiny_config();
  c.task.kind = TaskKind::directed;
  worker::EvaluateOptions o;
  o.evaluate_robot = [](const Config&, const tasks::Task&, const worker::BuiltRobot& robot,
                        const EvalRequest& req, const worker::EvaluateOptions&) {
    EvalResult r;
    r.fitness = 10.0 + req.unit;
    r.voxels = static_cast<std::int32_t>(robot.body.cells.size());
    return r;
  };
  const EvalResult r = evaluate_request(c, request_for(c, 3), o);
  EXPECT_EQ(r.unit, 3);
  EXPECT_EQ(r.fitness, 13.0);
}

TEST(EvaluateRequest, BuildRobotFillsMaterialsFromTheConfig) {
  const Config c = tiny_config();
  const evo::Population pop = evo::Population::create(c, 0, 5);
  const worker::BuiltRobot r =
      worker::build_robot(c, pop.members().front().genome, *tasks::make_task(c));
  EXPECT_TRUE(r.valid);
  EXPECT_TRUE(r.actuatable);
  ASSERT_EQ(r.body.materials.size(), static_cast<std::size_t>(c.physics.material_count));
  EXPECT_EQ(r.body.materials.front().youngs_modulus, c.physics.youngs_modulus_min);
  EXPECT_EQ(r.body.materials.back().youngs_modulus, c.physics.youngs_modulus_max);
  EXPECT_EQ(r.body.voxel_size, c.physics.voxel_size);
}

}  // namespace
