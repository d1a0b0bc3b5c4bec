// The hand-made pressure-driven oscillator of controller.init = "oscillator" (docs/model.md
// §4.8) on real bodies, without oscillator inputs: every chamber's pressure swings through full
// inflate/vent strokes, as many as the valve low-pass and the control frame allow and no more
// than they allow; perturbed genomes differ and stay oscillators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/rng.hpp"
#include "common/robot.hpp"
#include "evo/genome.hpp"
#include "tasks/task.hpp"
#include "tests/reference_data.hpp"
#include "tests/worker/two_chamber_block.hpp"
#include "worker/evaluate.hpp"

using namespace softevo;

namespace {

constexpr double kSeconds = 3.0;    // [s]
constexpr double kLowBar = 1.025;   // §4.8: the lower switching pressure [bar]
constexpr double kHighBar = 1.075;  // the upper one [bar]

Config oscillator_config() {
  Config c;
  c.task.control = ControlLoop::closed;
  c.task.eval_seconds = kSeconds;
  c.run.eval_timeout_seconds = 0.0;
  c.controller.oscillator_inputs = false;
  c.controller.init = ControllerInit::oscillator;
  return c;
}

// Full strokes per chamber: a cycle is counted when the pressure, having been below kLowBar,
// rises above kHighBar and then falls below kLowBar again.
struct Cycles {
  std::vector<int> count;
  std::vector<double> low, high;  // lowest and highest pressure after the first second [bar]
  EvalStatus status = EvalStatus::ok;
};

Cycles cycles_of(const Config& config, const BodyPlan& body, std::uint64_t seed) {
  const auto task = tasks::make_task(config);
  const evo::EvoParams params = evo::evo_params(config, task->controller_inputs());
  Rng rng(seed);
  evo::Genome genome;
  evo::oscillator_controller(params, rng, genome);
  const ControllerSpec spec = evo::to_controller_spec(genome, config, task->controller_inputs());
  EXPECT_EQ(spec.input_count(), 10);  // no sin/cos: the 10 pressure sensors only
  Cycles out;
  std::vector<int> phase;  // 0 = not yet low, 1 = low seen, 2 = high seen after low
  worker::EvaluateOptions opts;
  opts.on_frame = [&](const worker::TraceFrame& f) {
    if (out.count.empty()) {
      out.count.assign(f.pressures.size(), 0);
      phase.assign(f.pressures.size(), 0);
      out.low.assign(f.pressures.size(), 10.0);
      out.high.assign(f.pressures.size(), 0.0);
    }
    for (std::size_t q = 0; q < f.pressures.size(); ++q) {
      const double bar = f.pressures[q] / 1e5;
      if (f.time > 1.0) {
        out.low[q] = std::min(out.low[q], bar);
        out.high[q] = std::max(out.high[q], bar);
      }
      if (bar < kLowBar) {
        if (phase[q] == 2) ++out.count[q];
        phase[q] = 1;
      } else if (bar > kHighBar && phase[q] == 1) {
        phase[q] = 2;
      }
    }
  };
  out.status = worker::evaluate(config, *task, body, spec, 0, opts).status;
  return out;
}

// Bounds from the time constants (§3.5, §4.6): a stroke ends only after the controller has seen
// the pressure cross a threshold (at most one decision per 1/60 s frame) and the new command
// has passed the four valve low-pass sections, each with a group delay of 1/(Q 2 pi f_c) =
// 22.5 ms at f_c = 10 Hz, Q = 0.707: a stroke takes at least 4 x 22.5 ms = 90 ms, a cycle
// 180 ms. Filling or venting itself takes a few chamber time constants V / 0.025 (6 ms at
// 148 cm^3); with the 1/60 s frame, a stroke lasts at most about 90 + 17 + 5 x 6 ms, so a cycle
// takes at most about 0.3 s, and at least half as many cycles as that allows must happen.
constexpr double kMinCycleSeconds = 2 * 4 * 0.0225;  // [s]
constexpr double kMaxCycleSeconds = 0.3;             // [s]

void expect_oscillating(const Cycles& c, const std::string& what) {
  ASSERT_EQ(c.status, EvalStatus::ok) << what;
  ASSERT_FALSE(c.count.empty()) << what;
  const double most = kSeconds / kMinCycleSeconds;
  const double least = 0.5 * (kSeconds - 0.5) / kMaxCycleSeconds;  // after a 0.5 s start-up
  for (std::size_t q = 0; q < c.count.size(); ++q) {
    std::printf("%s chamber %zu: %d cycles in %.1f s, %.3f .. %.3f bar\n", what.c_str(), q,
                c.count[q], kSeconds, c.low[q], c.high[q]);
    EXPECT_GE(c.count[q], least) << what << " chamber " << q;
    EXPECT_LE(c.count[q], most) << what << " chamber " << q;
    // Full strokes: the delay lets each one run nearly from ambient to the 1.2 bar supply.
    EXPECT_LT(c.low[q], 1.01) << what << " chamber " << q;
    EXPECT_GT(c.high[q], 1.15) << what << " chamber " << q;
  }
}

}  // namespace

TEST(OscillatorInit, EveryChamberOfATestBlockCyclesWithinTheValveBounds) {
  const Config config = oscillator_config();
  expect_oscillating(cycles_of(config, test::two_chamber_block(), 1), "two-chamber block");
  expect_oscillating(cycles_of(config, test::two_chamber_block(), 2), "two-chamber block seed 2");
}

TEST(OscillatorInit, EveryChamberOfAThesisChampionBodyCycles) {
  // gait-closed-10: 5 chambers; its body with the hand-made controller instead of its own.
  const auto path = softevo::test::reference_bestbots() / "gait-closed-10.robot.json";
  if (!std::filesystem::exists(path))
    GTEST_SKIP() << "thesis champion not found at " << path << " (../shared/reference)";
  const RobotFile robot = read_robot_file(path.string());
  expect_oscillating(cycles_of(oscillator_config(), robot.body, 3), "gait-closed-10 body");
}

TEST(OscillatorInit, GenesAreTheConstructionPlusASmallPerturbation) {
  const Config config = oscillator_config();
  const evo::EvoParams params = evo::evo_params(config, 0);
  Rng a(5), b(6);
  evo::Genome ga, gb;
  evo::oscillator_controller(params, a, ga);
  evo::oscillator_controller(params, b, gb);
  EXPECT_NE(ga.controller.weights_hidden, gb.controller.weights_hidden);  // not identical
  const int h = params.shape.hidden;
  // Chamber q's sensor (input q) drives unit q mod H with -4; its valves +-3 from that unit.
  for (int q = 0; q < params.shape.outputs / 2; ++q) {
    for (int i = 0; i < h; ++i) {
      const double w = ga.controller.weights_hidden[static_cast<std::size_t>(q * h + i)];
      EXPECT_NEAR(w, i == q % h ? -4.0 : 0.0, 0.5) << "sensor " << q << " unit " << i;
    }
    const auto out = [&](int unit, int k) {
      return ga.controller.weights_out[static_cast<std::size_t>(unit * params.shape.outputs + k)];
    };
    EXPECT_NEAR(out(q % h, 2 * q), 3.0, 0.5);
    EXPECT_NEAR(out(q % h, 2 * q + 1), -3.0, 0.5);
  }
  for (double s : ga.step_sizes.weights_out) EXPECT_EQ(s, config.controller.init_perturbation_sd);
  EXPECT_EQ(ga.step_sizes.freq[0], config.controller.freq_step_size_init);

  Config open = config;
  open.task.control = ControlLoop::open;
  open.controller.oscillator_inputs = true;
  Rng c(7);
  evo::Genome gc;
  EXPECT_THROW(evo::oscillator_controller(evo::evo_params(open, 0), c, gc), std::invalid_argument);
}
