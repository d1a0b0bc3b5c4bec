// Elman network controller (docs/model.md §4). See controller.hpp.
#include "worker/controller.hpp"

#include "worker/elman_tanh.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

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

}  // namespace softevo::worker
