// Elman network controller with oscillator (docs/model.md §4), float32 as the reference
// (tiny-dnn with float_t = float).
//
// Per control frame (§5 frame steps 1-2): advance the oscillator phase (§4.2), assemble the inputs
// [sin, cos, (direction), (pressure sensors)] (§4.1), run the network (§4.3) and map the outputs
// to valve commands u = (y + 1)/2 (§4.5).
#pragma once

#include <span>
#include <vector>

#include "common/robot.hpp"

namespace softevo::worker {

// Immutable float32 weights of one controller (layouts of §4.4, input-major).
struct ElmanWeights {
  int inputs = 0;             // n_in: 2 + directed + 10 x closed (§4.1)
  int hidden = 0;             // H (= context units)
  int outputs = 0;            // 20 (2 x max chambers)
  std::vector<float> w_ih;    // (inputs x hidden), index c*H + i
  std::vector<float> b_h;     // (hidden)
  std::vector<float> w_ho;    // (hidden x outputs), index c*outputs + k
  std::vector<float> b_o;     // (outputs)
  std::vector<float> w_ch;    // (hidden x hidden), index c*H + i: context c -> hidden i
  std::vector<float> w_self;  // (hidden) diagonal context -> context
  std::vector<float> w_ctx;   // (hidden) diagonal hidden -> context
  std::vector<float> b_ctx;   // (hidden)
  float frequency = 0.0f;     // oscillator frequency [Hz] (loaded into float32, §4.4)
};

// Convert the double genome vectors to float32 (§4.4). Throws std::invalid_argument if a vector
// length does not match spec.input_count(), hidden, outputs.
ElmanWeights make_elman_weights(const ControllerSpec& spec);

// What changes between frames: oscillator phase and context units.
struct ElmanState {
  double phase = 0.0;          // oscillator phase phi [rad] (double, §4.2)
  std::vector<float> context;  // c(t-1) (hidden), initially 0
  std::vector<float> hidden;   // h(t) of the last frame (hidden), for traces
};

ElmanState initial_elman_state(const ElmanWeights& w);

// §4.2: phi += 2 pi (1/rate) f; wrap once by 2 pi if phi >= 2 pi.
void advance_oscillator(const ElmanWeights& w, ElmanState& s, double control_rate_hz);

// §4.3: one network evaluation; `inputs` has w.inputs values, `outputs` receives w.outputs raw
// tanh outputs y in (-1, 1). Updates the context. No allocation.
void elman_forward(const ElmanWeights& w, ElmanState& s, std::span<const float> inputs,
                   std::span<float> outputs);

// The controller of a robot as one control frame's mapping from what it senses to valve
// commands (§5 frame steps 1-2): oscillator advance, inputs [sin, cos, task inputs, pressure
// sensors] with the sensor part capped at 10 values and zero-padded (§4.1), network, u = (y + 1)/2.
// Task inputs the controller has but the task does not feed read 0; task inputs beyond the
// controller's are not fed.
class ElmanController {
 public:
  // Throws std::invalid_argument for controller vectors of the wrong length.
  ElmanController(const ControllerSpec& spec, double control_rate_hz,
                  bool ablate_oscillator = false, bool ablate_sensors = false);

  // One frame: `task_inputs` as the task gives them (Simulation::task_inputs), `sensor_bar`
  // the pressure sensor reading of every chamber [bar] (read only by a closed-loop controller),
  // `commands` receives 2 x chambers valve openings (2q inlet, 2q+1 outlet). Throws
  // std::invalid_argument when the controller has fewer than 2 x chambers outputs.
  void act(std::span<const float> task_inputs, std::span<const float> sensor_bar,
           std::span<float> commands);
  // Throws std::invalid_argument when the controller has fewer than 2 x `chambers` outputs.
  void check_chambers(int chambers) const;
  // The network inputs of the last act() (input_count values).
  std::span<const float> inputs() const { return inputs_; }
  const ElmanState& state() const { return brain_; }
  int input_count() const { return weights_.inputs; }
  int output_count() const { return weights_.outputs; }
  // Back to the state before the first frame (phase 0, context 0).
  void reset();

 private:
  ControllerSpec spec_;
  ElmanWeights weights_;
  ElmanState brain_;
  double control_rate_hz_;
  bool ablate_oscillator_;
  bool ablate_sensors_;
  std::vector<float> inputs_;
  std::vector<float> outputs_;
};

}  // namespace softevo::worker
