// Recording one evaluation as a trace (format softevo.trace/1, docs/trace.md): the frames an
// evaluation reports through its callbacks (worker::EvaluateOptions), buffered in memory and
// written once at the end. Used by `softevo eval --trace`; a steered viewer session is the next
// user.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "common/safe_write.hpp"
#include "worker/evaluate.hpp"

namespace softevo::motion {

// Frames are held in memory until the end: a trace of 3600 s of a 1000-voxel robot would need
// about 12 GB. Beyond this a trace is refused before the evaluation starts.
inline constexpr double kMaxTraceBytes = 4.0 * 1024 * 1024 * 1024;

// Bytes of the recorded frames (positions, orientations, pressures, valves, time) of `frames`
// frames of a body.
double trace_bytes(std::int64_t frames, const BodyPlan& body);

// Throws std::invalid_argument naming `path` when a trace of `body` over config's evaluation
// would need more than kMaxTraceBytes.
void check_trace_memory(const std::string& path, const Config& config, const BodyPlan& body);

class TraceRecorder {
 public:
  // Sets the options' on_start / on_frame callbacks to this recorder (which must outlive the
  // evaluation). A new start clears what an earlier unit recorded.
  void attach(worker::EvaluateOptions& options);
  bool started() const { return started_; }
  int frames() const { return frames_; }
  // Writes the recorded unit to `path` (io::write_trace, atomic; an existing file only with
  // Overwrite::replace). `direction_deg`: the traced unit's target direction, if the task has
  // one.
  void write(const std::string& path, const RobotFile& robot, const EvalResult& result,
             double control_rate, std::optional<double> direction_deg, Overwrite overwrite) const;

 private:
  bool started_ = false;
  int chambers_ = 0;
  int steps_per_frame_ = 0;
  double dt_ = 0.0;           // [s]
  double voxel_size_ = 0.0;   // [m]
  physics::Terrain terrain_;  // the evaluation's ground
  std::vector<int> voxel_cells_, voxel_material_;
  std::vector<double> positions_;     // [m], 3 per voxel per frame
  std::vector<double> orientations_;  // quaternion w, x, y, z per voxel per frame
  std::vector<double> pressures_;     // [Pa] per chamber per frame
  std::vector<float> valves_;         // commands in [0, 1], 2 per chamber per frame
  std::vector<double> time_;          // [s] per frame
  int frames_ = 0;
};

}  // namespace softevo::motion
