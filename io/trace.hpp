// Trace `softevo.trace/1` (HDF5): one simulated evaluation frame by frame, written by
// `softevo eval --trace` and read by `softevo render` and analysis scripts. The schema is
// documented in docs/trace.md; this header is its single implementation.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/safe_write.hpp"
#include "common/terrain_shape.hpp"

namespace softevo::io {

inline constexpr const char* kTraceFormat = "softevo.trace/1";

// What a trace may hold (docs/trace.md "Limits"): read_trace checks every extent against these
// before it allocates, and never reads more values than the file has bytes for.
struct TraceLimits {
  static constexpr std::int64_t voxels = 64 * 64 * 64;  // body.lattice <= 64 cells per axis
  static constexpr std::int64_t chambers = 64 * 64 * 64;
  static constexpr std::int64_t frames = 100'000'000;  // records (> 19 days at 60 Hz)
  static constexpr std::int64_t robot_json_bytes = 64LL << 20;
  static constexpr std::int64_t string_bytes = 4096;  // format, status
  // Values (docs/trace.md "Limits"): what a simulation can record, with room to spare.
  static constexpr std::int32_t lattice_cells = 64;   // voxel cell indices in [0, 64)
  static constexpr std::int32_t materials = 10;       // physics.material_count <= 10
  static constexpr double position_m = 1.0e4;         // |coordinate| of a voxel or of the ground
  static constexpr double max_voxel_size_m = 10.0;    // physics.voxel_size <= 10 m
  static constexpr double max_frame_rate_hz = 1.0e4;  // task.control_rate <= 10 kHz
  static constexpr double max_dt_s = 1.0;
};

// Everything a trace holds. Per-frame arrays are row-major with the frame index outermost.
struct Trace {
  std::int64_t frames = 0;
  std::int64_t voxels = 0;
  std::int64_t chambers = 0;
  std::vector<double> positions;             // [m] voxel centres [frames][voxels][3]
  std::vector<double> orientations;          // unit quaternions (w, x, y, z) [frames][voxels][4]
  std::vector<double> pressures;             // [Pa] absolute chamber pressure [frames][chambers]
  std::vector<float> valve_commands;         // openings in [0, 1] [frames][2 * chambers]
  std::vector<double> time;                  // [s] simulated time of each frame [frames]
  std::vector<std::int32_t> voxel_cells;     // lattice cell (i, j, k) [voxels][3]
  std::vector<std::int32_t> voxel_material;  // structural material 1..10 [voxels]
  std::string robot_json;                    // the robot file; "" = unknown (read only)
  double dt = 0.0;                           // [s] physics time step; 0 = unknown (read only)
  double voxel_size = 0.0;                   // [m] lattice pitch
  double frame_rate = 0.0;                   // [Hz] frames per simulated second
  std::int64_t steps_per_frame = 0;     // physics steps between frames; 0 = unknown (read only)
  std::optional<double> direction_deg;  // [deg] target direction (directed task only)
  std::optional<double> fitness;        // fitness of the evaluation
  std::string status;                   // EvalStatus name ("ok", ...); "" = unknown
  // The ground of the traced evaluation (docs/model.md §2.8a, docs/trace.md): what a viewer
  // needs to draw it (or to rebuild it with physics::make_terrain). Absent = flat.
  struct Terrain {
    std::string kind;    // "rows", "bumps", "steps" or "slope"
    std::string seed;    // the evaluation's terrain seed, 16 hex digits
    TerrainShape shape;  // the heightfield's numbers (common/terrain_shape.hpp)
    // Where the generated ground starts, as the evaluation laid it (make_terrain derives these
    // from the body's lattice, which a trace does not keep).
    double bumps_start_x = 0.0;  // [m] bumps fade in over one correlation length from here
    double first_riser_x = 0.0;  // [m] steps: centre-frame x of the first riser
    double slope_start = 0.0;    // [m] slope: distance along the direction where it starts
    std::vector<double> row_x;   // [m] rows: x of each row's voxel centres
    double row_y_min = 0.0, row_y_max = 0.0;  // [m] rows: y span of the rows' centres
  };
  std::optional<Terrain> terrain;

  // Throws std::invalid_argument naming the first array whose length does not match the
  // counts (`where` names the trace in the message).
  void check(const std::string& where) const;
  // Throws std::invalid_argument naming the first value a simulation cannot have recorded
  // (docs/trace.md "Limits"): a non-finite or out-of-range attribute (voxel_size, frame_rate,
  // dt, direction, fitness, the terrain's numbers), a position, quaternion or time that is not
  // finite or is out of range, times that go back, a voxel cell or material out of range. A
  // renderer or viewer may then rely on the geometry being sane. Pressures and valve commands
  // may be NaN (a chamber that encloses no volume) and are not checked.
  void check_values(const std::string& where) const;
};

// Writes `trace` to `path` atomically (common/safe_write.hpp: temporary file, fsync, rename;
// a symlink or special file is refused, an existing regular file replaced only with
// Overwrite::replace); every dataset and attribute of docs/trace.md. Throws std::runtime_error
// naming the file, the object and the reason.
void write_trace(const std::string& path, const Trace& trace,
                 Overwrite overwrite = Overwrite::refuse);

// Reads a trace. Only /positions, /orientations, /voxel_cells and /voxel_material are required,
// so that traces written by other tools can be drawn: a missing /time is f / frame_rate, a
// missing frame_rate 60 Hz (one frame per control frame), a missing voxel_size 0.01 m, missing
// pressures and valves leave chambers = 0. Throws std::runtime_error naming the file, the
// object and the reason (a missing required dataset, a wrong shape, a value that
// Trace::check_values refuses).
Trace read_trace(const std::string& path);

// `path` is an HDF5 file with a /positions dataset, the mark of a trace. Throws only for a file
// that crashes libhdf5 (std::runtime_error "damaged HDF5 file", io/open_probe.hpp).
bool is_trace(const std::string& path);

}  // namespace softevo::io
