// See trace_recorder.hpp.
#include "motion/trace_recorder.hpp"

#include <cmath>
#include <stdexcept>

#include "io/trace.hpp"
#include "physics/model.hpp"

namespace softevo::motion {

double trace_bytes(std::int64_t frames, const BodyPlan& body) {
  std::int64_t voxels = 0;
  for (int cell : body.cells) voxels += BodyPlan::is_structural(cell) ? 1 : 0;
  const std::int64_t chambers = body.chamber_count();
  const double per_frame = static_cast<double>(voxels) * (3 + 4) * sizeof(double) +
                           static_cast<double>(chambers) * (sizeof(double) + 2 * sizeof(float)) +
                           sizeof(double);
  return static_cast<double>(frames + 1) * per_frame;
}

void check_trace_memory(const std::string& path, const Config& config, const BodyPlan& body) {
  const auto frames = std::llround(config.task.control_rate * config.task.eval_seconds);
  const double bytes = trace_bytes(frames, body);
  if (bytes > kMaxTraceBytes)
    throw std::invalid_argument("--trace " + path + ": " + std::to_string(frames) +
                                " frames of this robot need " +
                                std::to_string(bytes / (1024.0 * 1024 * 1024)) +
                                " GiB in memory, more than the limit of 4 GiB; shorten "
                                "task.eval_seconds (--seconds)");
}

namespace {

// The ground as a trace records it (docs/trace.md).
std::optional<io::Trace::Terrain> trace_terrain(const physics::Terrain& t) {
  if (t.kind == physics::TerrainKind::flat) return std::nullopt;
  io::Trace::Terrain g;
  g.kind = softevo::to_string(t.kind);
  g.seed = hash_hex(t.params.seed);
  g.shape = t.params.shape;
  g.bumps_start_x = t.start_x;
  g.first_riser_x = t.first_riser_x;
  g.slope_start = t.start_d;
  if (t.kind == physics::TerrainKind::rows) {
    g.row_x.assign(t.row_x.begin(), t.row_x.end());
    g.row_y_min = t.row_y_min + t.voxel_size;  // the span of the row voxels' centres
    g.row_y_max = t.row_y_max - t.voxel_size;
  }
  return g;
}

}  // namespace

void TraceRecorder::attach(worker::EvaluateOptions& options) {
  options.on_start = [this](const worker::TraceHeader& h) {
    started_ = true;
    chambers_ = h.chambers;
    steps_per_frame_ = h.steps_per_frame;
    dt_ = h.model->dt;
    voxel_size_ = h.model->voxel_size;
    terrain_ = h.model->terrain;
    voxel_cells_.clear();
    voxel_material_.clear();
    for (int v = 0; v < h.model->voxel_count; ++v) {
      for (int i = 0; i < 3; ++i) voxel_cells_.push_back(h.model->voxel_cell[v][i]);
      voxel_material_.push_back(h.model->voxel_material[v]);
    }
    positions_.clear();
    orientations_.clear();
    pressures_.clear();
    valves_.clear();
    time_.clear();
    frames_ = 0;
  };
  options.on_frame = [this](const worker::TraceFrame& f) {
    for (const auto& p : f.positions) positions_.insert(positions_.end(), {p.x(), p.y(), p.z()});
    for (const auto& q : f.orientations)
      orientations_.insert(orientations_.end(), {q.w, q.x, q.y, q.z});
    pressures_.insert(pressures_.end(), f.pressures.begin(), f.pressures.end());
    valves_.insert(valves_.end(), f.valve_commands.begin(), f.valve_commands.end());
    time_.push_back(f.time);
    ++frames_;
  };
}

void TraceRecorder::write(const std::string& path, const RobotFile& robot, const EvalResult& result,
                          double control_rate, std::optional<double> direction_deg,
                          Overwrite overwrite) const {
  if (!started_) throw std::logic_error("TraceRecorder::write: nothing was recorded");
  io::Trace trace;
  trace.frames = frames_;
  trace.voxels = static_cast<std::int64_t>(voxel_material_.size());
  trace.chambers = chambers_;
  trace.positions = positions_;
  trace.orientations = orientations_;
  trace.pressures = pressures_;
  trace.valve_commands = valves_;
  trace.time = time_;
  trace.voxel_cells.assign(voxel_cells_.begin(), voxel_cells_.end());
  trace.voxel_material.assign(voxel_material_.begin(), voxel_material_.end());
  trace.robot_json = robot_to_json(robot);
  trace.dt = dt_;
  trace.voxel_size = voxel_size_;
  trace.frame_rate = control_rate;
  trace.steps_per_frame = steps_per_frame_;
  if (direction_deg) trace.direction_deg = *direction_deg;
  trace.terrain = trace_terrain(terrain_);
  trace.fitness = result.fitness;
  trace.status = to_string(result.status);
  io::write_trace(path, trace, overwrite);
}

}  // namespace softevo::motion
