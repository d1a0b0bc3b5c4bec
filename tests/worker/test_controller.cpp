// Elman controller (docs/model.md §4): network equations in float32, weight layouts, the
// oscillator phase, input counts.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "common/robot.hpp"
#include "physics/pneumatics.hpp"
#include "tests/test_controller_spec.hpp"
#include "worker/controller.hpp"

namespace {

using softevo::ControllerSpec;
using namespace softevo::worker;

// A spec whose every weight is distinct so that a layout mix-up changes the result.
ControllerSpec numbered_spec(bool closed, bool directed) {
  ControllerSpec s;
  s.closed_loop = closed;
  s.directed = directed;
  const int n = s.input_count(), h = 4, o = 20;
  auto fill = [](std::vector<double>& v, int count, double scale, double offset) {
    v.resize(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) v[i] = offset + scale * std::sin(1.0 + 0.7 * i);
  };
  fill(s.vectors.weights_hidden, n * h, 0.8, 0.0);
  fill(s.vectors.bias_hidden, h, 0.3, 0.1);
  fill(s.vectors.weights_out, h * o, 1.2, -0.1);
  fill(s.vectors.bias_out, o, 0.5, 0.0);
  fill(s.vectors.weights_recurrent, h * h, 0.6, 0.0);
  fill(s.vectors.weights_recurrent_self, h, 0.4, 0.2);
  fill(s.vectors.weights_context, h, 0.9, 0.0);
  fill(s.vectors.bias_context, h, 0.2, -0.05);
  s.vectors.freq = {3.2};
  return s;
}

// §4.3 written out in double from the genome vectors (layouts of §4.4).
struct Reference {
  std::vector<double> context;
  std::vector<double> forward(const ControllerSpec& s, const std::vector<double>& x) {
    const int n = s.input_count(), h = 4, o = 20;
    const auto& v = s.vectors;
    if (context.empty()) context.assign(h, 0.0);
    std::vector<double> hid(h), y(o);
    for (int i = 0; i < h; ++i) {
      double a = v.bias_hidden[i];
      for (int c = 0; c < n; ++c) a += v.weights_hidden[c * h + i] * x[c];
      for (int c = 0; c < h; ++c) a += v.weights_recurrent[c * h + i] * context[c];
      hid[i] = std::tanh(a);
    }
    for (int k = 0; k < o; ++k) {
      double a = v.bias_out[k];
      for (int c = 0; c < h; ++c) a += v.weights_out[c * o + k] * hid[c];
      y[k] = std::tanh(a);
    }
    for (int i = 0; i < h; ++i)
      context[i] = std::tanh(v.weights_context[i] * hid[i] +
                             v.weights_recurrent_self[i] * context[i] + v.bias_context[i]);
    return y;
  }
};

}  // namespace

TEST(Controller, InputCountsFollowControlAndDirected) {
  EXPECT_EQ(numbered_spec(false, false).input_count(), 2);
  EXPECT_EQ(numbered_spec(true, false).input_count(), 12);
  EXPECT_EQ(numbered_spec(false, true).input_count(), 3);
  EXPECT_EQ(numbered_spec(true, true).input_count(), 13);
}

TEST(Controller, WithoutOscillatorInputsTheSensorsComeFirst) {
  // controller.oscillator_inputs = false (§4.1): [task inputs, pressure sensors], no sin/cos.
  ControllerSpec spec = softevo::test::make_controller(
      true, true, [](int i) { return std::sin(0.3 * i); }, 2.0);
  spec.oscillator_inputs = false;
  spec.vectors.weights_hidden.resize(static_cast<std::size_t>(11 * spec.hidden));
  EXPECT_EQ(spec.input_count(), 11);
  ElmanController brain(spec, 60.0);
  const std::vector<float> direction = {0.25f};
  const std::vector<float> sensor_bar = {1.1f, 1.0f, 0.9f};
  std::vector<float> commands(6);
  brain.act(direction, sensor_bar, commands);
  ASSERT_EQ(brain.inputs().size(), 11u);
  EXPECT_EQ(brain.inputs()[0], 0.25f);
  for (int q = 0; q < 3; ++q)
    EXPECT_EQ(brain.inputs()[1 + q], softevo::physics::pressure_sensor_input(sensor_bar[q]));
  for (std::size_t c = 4; c < 11; ++c) EXPECT_EQ(brain.inputs()[c], 0.0f);
}

TEST(Controller, ElmanMatchesTheEquationsOverSeveralFrames) {
  for (bool closed : {false, true}) {
    for (bool directed : {false, true}) {
      const ControllerSpec spec = numbered_spec(closed, directed);
      const ElmanWeights w = make_elman_weights(spec);
      ElmanState st = initial_elman_state(w);
      Reference ref;
      std::vector<float> out(20);
      for (int frame = 0; frame < 20; ++frame) {
        std::vector<float> x(static_cast<std::size_t>(w.inputs));
        std::vector<double> xd(x.size());
        for (std::size_t c = 0; c < x.size(); ++c) {
          x[c] = static_cast<float>(std::cos(0.3 * frame + 1.1 * c) * (c >= 2 ? 3.0 : 1.0));
          xd[c] = x[c];
        }
        elman_forward(w, st, x, out);
        const std::vector<double> y = ref.forward(spec, xd);
        for (int k = 0; k < 20; ++k)
          ASSERT_NEAR(out[k], y[k], 2e-5) << "closed " << closed << " directed " << directed
                                          << " frame " << frame << " output " << k;
      }
    }
  }
}

TEST(Controller, ContextCarriesMemory) {
  // Same input twice: the outputs differ because the context changed (recurrence is wired).
  const ControllerSpec spec = numbered_spec(false, false);
  const ElmanWeights w = make_elman_weights(spec);
  ElmanState st = initial_elman_state(w);
  const std::vector<float> x = {0.5f, -0.25f};
  std::vector<float> a(20), b(20);
  elman_forward(w, st, x, a);
  elman_forward(w, st, x, b);
  EXPECT_NE(a, b);
}

TEST(Controller, OscillatorAdvancesBeforeReadingAndWraps) {
  const ElmanWeights w = make_elman_weights(numbered_spec(false, false));  // f = 3.2 Hz
  ElmanState st = initial_elman_state(w);
  const double step = 2.0 * std::numbers::pi / 60.0 * static_cast<double>(w.frequency);
  advance_oscillator(w, st, 60.0);
  EXPECT_DOUBLE_EQ(st.phase, step);  // first frame already reads phi = 2 pi f / 60
  double expected = step;
  for (int i = 1; i < 600; ++i) {
    advance_oscillator(w, st, 60.0);
    expected += step;
    if (expected >= 2.0 * std::numbers::pi) expected -= 2.0 * std::numbers::pi;
    ASSERT_GE(st.phase, 0.0);
    ASSERT_LT(st.phase, 2.0 * std::numbers::pi);
  }
  EXPECT_NEAR(st.phase, expected, 1e-9);
  // After 600 frames (10 s at 3.2 Hz = 32 whole periods) the phase is back near 0 (mod 2 pi).
  EXPECT_NEAR(std::fmod(st.phase + 1e-4, 2.0 * std::numbers::pi), 1e-4, 1e-5);  // f is float
}

TEST(Controller, WrongVectorLengthIsAnError) {
  ControllerSpec spec = numbered_spec(true, false);
  spec.vectors.weights_hidden.pop_back();
  EXPECT_THROW(make_elman_weights(spec), std::invalid_argument);
}
