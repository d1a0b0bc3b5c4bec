// Where a robot and its motion come from: a robot file, an `eval --trace` HDF5 file
// (docs/trace.md), or one individual of a run archive (its genome developed and re-simulated
// with the archived config, exactly as the run evaluated it). Used by `softevo render`,
// `softevo replay` and the viewer (view/).
//
// Its own room rather than io/: it re-simulates (worker/), develops genomes (evo/) and builds
// bodies and poses (scene/), while io/ is the storage layer that master/ and softevo-mpi link
// and that must stay free of those.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "physics/terrain.hpp"
#include "scene/scene.hpp"

namespace softevo::motion {

// A body and its poses over time (one pose = static).
struct Motion {
  scene::Body body;
  std::vector<scene::Pose> poses;       // ascending in time
  std::string name;                     // label for pictures
  std::optional<double> direction_deg;  // target direction the motion was simulated towards
  std::string summary;                  // one line: fitness and status when simulated, "" otherwise
  physics::Terrain terrain;             // the ground it moved on (flat unless the config says)
  std::string status;                   // status of the simulation or trace, "" for a still
};

// What the poses of a re-simulation or trace may hold in memory at most (positions and
// orientations of every voxel of every kept pose): beyond it a render is refused before it
// simulates, naming the pose count and what to lower. The same bound as a trace's.
inline constexpr double kMaxMotionBytes = 4.0 * 1024 * 1024 * 1024;

struct MotionRequest {
  bool needs_motion = false;  // robot file / archive: simulate (else the rest pose is drawn)
  bool static_pose = false;   // never simulate
  std::optional<double> direction_deg;  // directed task: target direction [deg]
  std::optional<double> seconds;        // simulated time [s] (default task.eval_seconds)
  // Archive selection.
  std::optional<std::int64_t> generation;  // default: the last generation
  std::optional<std::int64_t> id;          // default: the best
  bool best = false;
  // Robot files: config to simulate with (default: thesis defaults of common/config.hpp).
  std::string config_file;
  std::vector<std::string> overrides;
  // Traces: robot file that gives the chamber cells.
  std::string robot_file;
  // The times [s] the output shows, given the time of the motion's last pose. Set: only the
  // first and last pose and, for each time, the pose nearest to it (render/compose.hpp
  // pose_at's choice) are kept, so a still or a time-lapse of an hour-long re-simulation holds
  // a few poses, and a video one per frame. Unset: every control frame is kept.
  std::function<std::vector<double>(double end)> shown_times;
};

// Dispatches on the input: *.json = robot file; HDF5 with root attribute format
// "softevo.run/1" = run archive; HDF5 with a /positions dataset = trace. Throws
// std::runtime_error / std::invalid_argument naming the file and the problem.
Motion load_motion(const std::string& input, const MotionRequest& request);

// One individual of a run archive, with everything needed to evaluate it again.
struct ArchivedIndividual {
  std::string archive_path;
  std::string config_text;  // /config, verbatim
  Config config;            // parsed from config_text
  std::string experiment;   // root attribute
  std::int64_t generation = 0;
  std::int64_t id = 0;
  std::size_t row = 0;      // row in the generation's table
  std::uint8_t status = 0;  // archived EvalStatus
  double fitness = 0.0;     // archived fitness
  std::int32_t voxels = 0;
  std::int32_t chambers = 0;
  std::vector<std::uint8_t> genome;  // encoded genome (the learned one in a learning run)
  int units = 1;                     // rows of `components`: work units of the genome
  // Archived fitness components [units][component_columns.size()] (docs/archive.md).
  std::vector<std::string> component_columns;
  std::vector<double> components;
};

// The generation numbers stored in an archive (ascending). Throws naming the file.
std::vector<std::int64_t> archived_generations(const std::string& archive_path);
// Every individual of one generation (default: the last), rows in id order.
std::vector<ArchivedIndividual> archived_generation(const std::string& archive_path,
                                                    std::optional<std::int64_t> generation);
// One individual: `id` (from `generation`, by default the last generation that holds it), or
// (no id) the best of the generation (default: the last; highest fitness, lowest id on ties).
// Throws when the generation or id is not in the archive, naming the generations that hold it.
ArchivedIndividual archived_individual(const std::string& archive_path,
                                       std::optional<std::int64_t> generation,
                                       std::optional<std::int64_t> id);

// Robot (body plan with materials and voxel size from the config, controller) of an archived
// genome, developed exactly as the worker does. Throws std::runtime_error for an invalid body.
RobotFile robot_of(const ArchivedIndividual& individual);

}  // namespace softevo::motion
