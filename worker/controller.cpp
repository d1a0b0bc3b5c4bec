// Elman network controller (docs/model.md §4). See controller.hpp.
#include "worker/controller.hpp"

#include "worker/elman_tanh.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "physics/pneumatics.hpp"

namespace softevo::worker {
namespace {

std::vector<float> to_float(const std::vector<double>& v, std::size_t expected, const char* name) {
  if (v.size() != expected)
    throw std::invalid_argument(std::string("controller vector '") + name + "' has " +
                                std::to_string(v.size()) + " values, expected " +
                                std::to_string(expected));
  std::vector<float> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = static_cast<float>(v[i]);
  return out;
}

}  // namespace

ElmanWeights make_elman_weights(const ControllerSpec& spec) {
  if (spec.hidden < 1 || spec.outputs < 1)
    throw std::invalid_argument("controller: hidden and outputs must be >= 1");
  ElmanWeights w;
  w.inputs = spec.input_count();
  w.hidden = spec.hidden;
  w.outputs = spec.outputs;
  const auto n = static_cast<std::size_t>(w.inputs), h = static_cast<std::size_t>(w.hidden),
             o = static_cast<std::size_t>(w.outputs);
  const ControllerVectors& v = spec.vectors;
  w.w_ih = to_float(v.weights_hidden, n * h, "weights_hidden");
  w.b_h = to_float(v.bias_hidden, h, "bias_hidden");
  w.w_ho = to_float(v.weights_out, h * o, "weights_out");
  w.b_o = to_float(v.bias_out, o, "bias_out");
  w.w_ch = to_float(v.weights_recurrent, h * h, "weights_recurrent");
  w.w_self = to_float(v.weights_recurrent_self, h, "weights_recurrent_self");
  w.w_ctx = to_float(v.weights_context, h, "weights_context");
  w.b_ctx = to_float(v.bias_context, h, "bias_context");
  w.frequency = to_float(v.freq, 1, "freq")[0];
  return w;
}

ElmanState initial_elman_state(const ElmanWeights& w) {
  ElmanState s;
  s.context.assign(static_cast<std::size_t>(w.hidden), 0.0f);  // c(-1) = 0 (§4.3)
  s.hidden.assign(static_cast<std::size_t>(w.hidden), 0.0f);
  return s;
}

void advance_oscillator(const ElmanWeights& w, ElmanState& s, double control_rate_hz) {
  // §4.2: phi += 2 pi * (1/60) * f (double); one wrap by 2 pi.
  constexpr double two_pi = 2.0 * std::numbers::pi;
  s.phase += two_pi * (1.0 / control_rate_hz) * static_cast<double>(w.frequency);
  if (s.phase >= two_pi) s.phase -= two_pi;
}

void elman_forward(const ElmanWeights& w, ElmanState& s, std::span<const float> inputs,
                   std::span<float> outputs) {
  const int n = w.inputs, h = w.hidden, o = w.outputs;
  // Fully connected layers as tiny-dnn computes them (float): out[i] = sum_c in[c] W[c n_out + i],
  // summed in input order, then + bias[i].
  for (int i = 0; i < h; ++i) {
    float from_input = 0.0f;
    for (int c = 0; c < n; ++c) from_input += w.w_ih[c * h + i] * inputs[c];
    from_input += w.b_h[i];
    float from_context = 0.0f;  // context -> hidden layer; its bias is never set (0, §4.3)
    for (int c = 0; c < h; ++c) from_context += w.w_ch[c * h + i] * s.context[c];
    s.hidden[i] = tanh_binary32(from_input + from_context);  // h(t)
  }
  for (int k = 0; k < o; ++k) {
    float a = 0.0f;
    for (int c = 0; c < h; ++c) a += w.w_ho[c * o + k] * s.hidden[c];
    a += w.b_o[k];
    outputs[k] = tanh_binary32(a);  // y(t)
  }
  // c(t) = tanh(w_ctx * h(t) + (w_self * c(t-1) + b_ctx)); the hidden -> context bias is 0.
  for (int i = 0; i < h; ++i) {
    const float from_hidden = w.w_ctx[i] * s.hidden[i];
    const float from_self = w.w_self[i] * s.context[i] + w.b_ctx[i];
    s.context[i] = tanh_binary32(from_hidden + from_self);
  }
}

ElmanController::ElmanController(const ControllerSpec& spec, double control_rate_hz,
                                 bool ablate_oscillator, bool ablate_sensors)
    : spec_(spec),
      weights_(make_elman_weights(spec)),
      brain_(initial_elman_state(weights_)),
      control_rate_hz_(control_rate_hz),
      ablate_oscillator_(ablate_oscillator),
      ablate_sensors_(ablate_sensors),
      inputs_(static_cast<std::size_t>(weights_.inputs), 0.0f),
      outputs_(static_cast<std::size_t>(weights_.outputs), 0.0f) {}

void ElmanController::reset() {
  brain_ = initial_elman_state(weights_);
  std::fill(inputs_.begin(), inputs_.end(), 0.0f);
}

void ElmanController::check_chambers(int chambers) const {
  if (2 * chambers > weights_.outputs)
    throw std::invalid_argument(
        std::to_string(chambers) + " chambers need " + std::to_string(2 * chambers) +
        " controller outputs, controller has " + std::to_string(weights_.outputs));
}

void ElmanController::act(std::span<const float> task_inputs, std::span<const float> sensor_bar,
                          std::span<float> commands) {
  const int chambers = static_cast<int>(sensor_bar.size());
  check_chambers(chambers);
  if (commands.size() != 2 * sensor_bar.size())
    throw std::invalid_argument("ElmanController::act: " + std::to_string(commands.size()) +
                                " valve commands for " + std::to_string(chambers) + " chambers");
  constexpr int kMaxSensorValues = 10;                     // §4.1: cap after the oscillator inputs
  advance_oscillator(weights_, brain_, control_rate_hz_);  // §4.2: before the inputs are read
  const int oscillator_inputs = spec_.oscillator_input_count();  // 2, or 0 without (§4.1)
  if (oscillator_inputs > 0) {
    inputs_[0] = ablate_oscillator_ ? 0.0f : static_cast<float>(std::sin(brain_.phase));
    inputs_[1] = ablate_oscillator_ ? 0.0f : static_cast<float>(std::cos(brain_.phase));
  }
  std::fill(inputs_.begin() + oscillator_inputs, inputs_.end(), 0.0f);
  const int sensor_slots = weights_.inputs - oscillator_inputs;
  int sensor = 0;
  auto push_sensor = [&](float value) {
    if (sensor < kMaxSensorValues && sensor < sensor_slots)
      inputs_[oscillator_inputs + sensor] = value;
    ++sensor;
  };
  const int fed_task_inputs = std::min(static_cast<int>(task_inputs.size()), spec_.task_inputs());
  for (int i = 0; i < fed_task_inputs; ++i) push_sensor(task_inputs[i]);
  for (int i = fed_task_inputs; i < spec_.task_inputs(); ++i) push_sensor(0.0f);
  if (spec_.closed_loop)
    for (int q = 0; q < chambers; ++q)
      push_sensor(ablate_sensors_ ? 0.0f : physics::pressure_sensor_input(sensor_bar[q]));
  // Network -> valve commands (y + 1)/2, output 2q inlet / 2q+1 outlet of chamber q (§4.5).
  elman_forward(weights_, brain_, inputs_, outputs_);
  for (std::size_t k = 0; k < commands.size(); ++k) commands[k] = (outputs_[k] + 1.0f) / 2.0f;
}

}  // namespace softevo::worker
