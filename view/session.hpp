// What `softevo view` shows: the input it was started with (a robot file, one archived
// individual, or a trace) and a session over it, a timeline of frames that grows while the robot
// is simulated live (robot files and archive individuals) or is known from the start (traces).
//
// A live session is worker::Simulation driven by the robot's own worker::ElmanController, one
// control frame per advance(), exactly the loop of worker::evaluate: an unsteered session gives
// evaluate's bits. Steering (directed task only) replaces the direction sensor input (§7.3) by
// the sensor towards the steered target direction, computed by tasks::direction_sensor from
// the same centroid and heading the task uses; the steering log (frame, direction) is the
// only other input, so a session is a pure function of its input and its log.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "common/safe_write.hpp"
#include "motion/robot_source.hpp"
#include "physics/terrain.hpp"
#include "render/render.hpp"
#include "scene/scene.hpp"
#include "tasks/task.hpp"

namespace softevo::view {

// How the input is turned into something to watch (the command's options).
struct ViewRequest {
  std::string config_file;                 // robot files: config to simulate with
  std::vector<std::string> overrides;      // robot files: section.key=value
  std::string task;                        // robot files: task name ("" = the controller's)
  std::optional<double> seconds;           // simulated time [s] (default task.eval_seconds)
  std::optional<double> direction_deg;     // directed task: initial target direction [deg]
  std::optional<std::int64_t> generation;  // archive: default the last
  std::optional<std::int64_t> id;          // archive: default the best
  std::string robot_file;                  // traces: robot file giving the chamber cells
};

enum class InputKind { robot, archive, trace };
}  // namespace softevo::view
template <>
struct softevo::ChoiceNames<softevo::view::InputKind> {
  static constexpr std::array<const char*, 3> names = {"robot", "archive", "trace"};
};
namespace softevo::view {

// The loaded input. Live inputs carry the robot and the resolved config; a trace carries its
// frames.
struct ViewInput {
  InputKind kind = InputKind::robot;
  std::string name;  // label of the robot
  scene::Body body;
  // Live inputs.
  RobotFile robot;
  Config config;
  std::optional<motion::ArchivedIndividual> archived;
  // Traces: every frame and the valve commands [frames][2 x chambers] (may be empty).
  motion::Motion trace_motion;
  std::vector<float> trace_valves;
  std::optional<double> trace_fitness;
  std::string trace_status;
  bool live() const { return kind != InputKind::trace; }
};

// Throws std::runtime_error / std::invalid_argument naming the file and the problem.
ViewInput load_view_input(const std::string& path, const ViewRequest& request);

// One steering command: from control frame `frame` on, the direction sensor points at
// `direction_deg` (counter-clockwise from +x, §7.2).
struct SteerCommand {
  int frame = 0;
  double direction_deg = 0.0;
  bool operator==(const SteerCommand&) const = default;
};
// The steering log as JSON ({"format":"softevo.steering/1","commands":[[frame,deg],...]}) and
// back; parse throws std::invalid_argument naming `source` and the problem (frames must be
// ascending and >= 0, directions finite within [-180, 180]).
std::string steering_log_json(const std::vector<SteerCommand>& log, const std::string& input_name);
std::vector<SteerCommand> parse_steering_log(const std::string& text, const std::string& source);

// One frame of the timeline, in the compact form the page draws (float32 is plenty for
// drawing; the bits of the simulation are kept in double by the trace recorder).
struct FrameRecord {
  int frame = 0;      // record index: control frame f, or frames() for the final state
  double time = 0.0;  // [s]
  // Voxel centres, then chamber cells placed between their walls (render::place_chambers) [m].
  std::vector<float> positions;
  // Unit quaternions (w, x, y, z) of the same items x 32767.
  std::vector<std::int16_t> orientations;
  std::vector<float> pressures_pa;             // absolute chamber pressure [Pa]
  std::vector<float> valves;                   // valve openings [0, 1] (2 per chamber)
  std::vector<float> components;               // fitness components so far (task order)
  float fitness = 0.0f;                        // fitness so far (final at the last record)
  float centroid_x = 0.0f, centroid_y = 0.0f;  // centroid displacement [m]
  float heading_rad = 0.0f;                    // mean rotation vector z [rad]
  float target_deg = 0.0f;                     // direction the sensor points at [deg]
};

class Session {
 public:
  // Throws std::invalid_argument for a bad steering log or a robot that cannot be simulated.
  explicit Session(const ViewInput& input, std::vector<SteerCommand> steering = {});
  // The session keeps a reference to its input: a temporary would dangle.
  explicit Session(ViewInput&& input, std::vector<SteerCommand> steering = {}) = delete;
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const ViewInput& input() const { return input_; }
  bool live() const { return input_.live(); }
  // The robot takes a target direction that can be changed while it runs (its task says so:
  // tasks::Task::steerable); the page's "directed" field.
  bool steerable() const;
  // Records of the whole session (control frames + 1 for the final state; a killed robot ends
  // earlier) and the records available so far.
  int planned_records() const { return planned_; }
  int records() const { return static_cast<int>(timeline_.size()); }
  const FrameRecord& record(int index) const {
    return timeline_.at(static_cast<std::size_t>(index));
  }
  // Simulates one more control frame (live) and appends its record; false when the session has
  // ended (every frame, killed, diverged, or a trace).
  bool advance();
  bool finished() const;
  EvalStatus status() const;
  std::string status_message() const;
  double control_rate() const;  // [Hz] records per simulated second
  std::vector<std::string> component_names() const;
  // Their units ("cm", "deg", ...; same order) and the unit of the fitness (the task's).
  std::vector<std::string> component_units() const;
  std::string fitness_unit() const;
  // The ground the robot moves on (docs/model.md §2.8a): the simulation's own (live) or the one
  // the trace recorded.
  const physics::Terrain& terrain() const;

  // Steering at the live head: from the next simulated frame on. Throws std::logic_error when
  // the robot is not directed, the session is not live or has ended.
  void steer(double direction_deg);
  const std::vector<SteerCommand>& steering_log() const { return steering_; }
  // The unit's result once finished (fitness and components as evaluate scores them).
  const std::optional<EvalResult>& result() const { return result_; }

  // Writes the session as a trace (softevo.trace/1, docs/trace.md) and its steering log beside
  // it (`trace_path` with .steering.json). Throws std::logic_error before the session finished.
  void save(const std::string& trace_path, Overwrite overwrite) const;

 private:
  struct Live;
  void append_live_record(int frame);
  void append_trace_record(int index);

  const ViewInput& input_;
  std::vector<SteerCommand> steering_;
  std::size_t next_command_ = 0;
  double target_deg_ = 0.0;
  std::unique_ptr<Live> live_;
  std::vector<FrameRecord> timeline_;
  int planned_ = 0;
  std::optional<EvalResult> result_;
};

// The ground of a session sampled for drawing: surface heights [m] (physics::terrain_height, half
// a voxel below the height a voxel centre rests at, as `softevo render` draws it) on a square
// lattice of points, x fastest. Empty (nx = 0) for the flat floor.
struct TerrainGrid {
  std::string kind;       // to_string of the terrain kind
  double x0 = 0, y0 = 0;  // first sample [m]
  double step = 0;        // grid spacing [m]
  int nx = 0, ny = 0;     // samples along x, y
  std::vector<float> z;   // [ny][nx] surface height [m]
  // Whether (x, y) [m] lies inside the grid at least `margin` [m] from each edge.
  bool covers(double x, double y, double margin) const;
};
// How far [m] the grid reaches beyond the robot's path, and the most samples along one side.
inline constexpr double kTerrainGridMargin = 1.0;
inline constexpr int kTerrainGridMaxSide = 401;
// Absolute centroid (x, y) [m] of a record's items.
std::array<double, 2> record_centre(const FrameRecord& record);
// The grid under every record so far (the whole path of a trace or a finished session; the
// path up to now of a live one), `margin` [m] beyond it on each side. Samples lie on the
// lattice of multiples of the step, so grids sent one after another agree where they overlap;
// the step is the voxel size, coarser only when a side would exceed kTerrainGridMaxSide.
TerrainGrid terrain_grid(const Session& session, double margin = kTerrainGridMargin);
// The grid a page needs next: nullopt while the record's centroid is at least margin / 2 inside
// `shown` (the grid it has), else terrain_grid of the records so far. A flat ground never needs
// one.
std::optional<TerrainGrid> terrain_update(const Session& session, const TerrainGrid& shown,
                                          int record, double margin = kTerrainGridMargin);

// Path of the steering log beside a trace: X.h5 -> X.steering.json.
std::string steering_log_path(const std::string& trace_path);

}  // namespace softevo::view
