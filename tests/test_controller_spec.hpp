// A complete, active Elman controller (§4) for tests that need one: every weight vector
// sized for the controller's inputs and filled from a smooth pattern.
#pragma once

#include <functional>
#include <vector>

#include "common/robot.hpp"

namespace softevo::test {

// Weight i of a vector with scale s is s * pattern(i); the oscillator runs at freq_hz.
inline ControllerSpec make_controller(bool closed_loop, bool directed,
                                      const std::function<double(int)>& pattern, double freq_hz) {
  ControllerSpec c;
  c.closed_loop = closed_loop;
  c.directed = directed;
  auto fill = [&](std::vector<double>& v, int count, double scale) {
    v.resize(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) v[i] = scale * pattern(i);
  };
  fill(c.vectors.weights_hidden, c.input_count() * 4, 1.5);
  fill(c.vectors.bias_hidden, 4, 0.5);
  fill(c.vectors.weights_out, 80, 2.0);
  fill(c.vectors.bias_out, 20, 0.5);
  fill(c.vectors.weights_recurrent, 16, 0.5);
  fill(c.vectors.weights_recurrent_self, 4, 0.5);
  fill(c.vectors.weights_context, 4, 0.5);
  fill(c.vectors.bias_context, 4, 0.1);
  c.vectors.freq = {freq_hz};
  return c;
}

}  // namespace softevo::test
