#include "motion/robot_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "common/eval_types.hpp"
#include "common/round_trip.hpp"
#include "evo/genome.hpp"
#include "io/archive.hpp"
#include "io/run_lock.hpp"
#include "io/trace.hpp"
#include "tasks/task.hpp"
#include "worker/evaluate.hpp"

namespace softevo::motion {

namespace {

namespace fs = std::filesystem;

bool is_json(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".json";
}

scene::Pose pose_of(const worker::TraceFrame& frame) {
  scene::Pose pose;
  pose.time = frame.time;
  pose.position.assign(frame.positions.begin(), frame.positions.end());
  pose.orientation.reserve(frame.orientations.size());
  for (const auto& q : frame.orientations) pose.orientation.emplace_back(q.w, q.x, q.y, q.z);
  pose.chamber_pressure.assign(frame.pressures.begin(), frame.pressures.end());
  return pose;
}

// Of poses offered in ascending time, keeps the first, the last and for each wanted time the
// nearest one (the earlier of two equally near, as render::pose_at chooses), holding at most one
// pose besides those; nullopt = keeps every pose.
class NearestPoses {
 public:
  explicit NearestPoses(std::optional<std::vector<double>> wanted) : wanted_(std::move(wanted)) {
    if (wanted_) std::sort(wanted_->begin(), wanted_->end());
  }
  void offer(scene::Pose pose) {
    if (!wanted_) {
      kept_.push_back(std::move(pose));
      return;
    }
    bool keep_new = !previous_;  // the first pose: the camera and the target line start there
    for (; next_ < wanted_->size() && (*wanted_)[next_] <= pose.time; ++next_) {
      const double t = (*wanted_)[next_];
      if (!previous_ || std::abs(pose.time - t) < std::abs(previous_->time - t)) {
        keep_new = true;
      } else {
        previous_needed_ = true;
      }
    }
    if (previous_ && previous_needed_) kept_.push_back(std::move(*previous_));
    previous_ = std::move(pose);
    previous_needed_ = keep_new;
  }
  // The kept poses, ascending; the last pose is among them (a clip's end is its time).
  std::vector<scene::Pose> finish() {
    if (previous_) kept_.push_back(std::move(*previous_));
    previous_.reset();
    return std::move(kept_);
  }

 private:
  std::optional<std::vector<double>> wanted_;
  std::size_t next_ = 0;  // first wanted time later than every pose offered so far
  std::optional<scene::Pose> previous_;
  bool previous_needed_ = false;
  std::vector<scene::Pose> kept_;
};

// Refuses, before anything is simulated, a motion whose kept poses would need more than
// kMaxMotionBytes.
void check_motion_memory(const std::string& name, double poses, std::size_t voxels) {
  const double bytes =
      poses * static_cast<double>(voxels) * (sizeof(Eigen::Vector3d) + sizeof(Eigen::Quaterniond));
  if (bytes <= kMaxMotionBytes) return;
  char message[320];
  std::snprintf(message, sizeof message,
                "%s: showing %.0f poses of %zu voxels needs %.1f GiB of memory, more than the "
                "limit of %.0f GiB; lower --seconds or --fps, or render a still or a time-lapse",
                name.c_str(), poses, voxels, bytes / (1024.0 * 1024 * 1024),
                kMaxMotionBytes / (1024.0 * 1024 * 1024));
  throw std::invalid_argument(message);
}

// The one direction a directed robot is shown walking towards: the request's, else the task's
// first; none for a gait controller.
std::optional<double> shown_direction(const Config& config, const ControllerSpec& controller,
                                      const MotionRequest& request) {
  if (!controller.directed) return std::nullopt;
  if (request.direction_deg) return request.direction_deg;
  return config.task.directions.empty() ? 0.0 : config.task.directions[0];
}

// Re-simulates and keeps the control frames (60 Hz) the output shows as poses.
Motion simulate_motion(Config config, const BodyPlan& plan, const ControllerSpec& controller,
                       const MotionRequest& request, const std::string& name,
                       const worker::EvaluationIds& ids = {}) {
  Motion motion;
  motion.body = scene::body_from_plan(plan, static_cast<int>(config.physics.material_count));
  motion.name = name;
  // Values of command options go through the config's range checks (--seconds nan or 1e10
  // would otherwise run 10 s or fail deep inside the simulation).
  std::vector<std::string> overrides;
  if (request.seconds) overrides.push_back("task.eval_seconds=" + toml_number(*request.seconds));
  if (const auto deg = shown_direction(config, controller, request)) {
    // One direction only (any direction can be shown; the fitness then belongs to it alone).
    overrides.push_back("task.directions=[" + toml_number(*deg) + "]");
    motion.direction_deg = deg;
  }
  if (!overrides.empty()) config = apply_overrides(config, overrides);
  const std::unique_ptr<tasks::Task> task = tasks::make_task(config);
  // The shown times follow from the end: planned from the evaluation's length, and planned
  // again from the real end when the simulation stopped early (a failed robot); the second run
  // gives the same bits, so it keeps exactly the poses the first would have needed.
  const double planned_end = config.task.eval_seconds;
  std::optional<std::vector<double>> wanted;
  if (request.shown_times) wanted = request.shown_times(planned_end);
  const double poses = wanted ? static_cast<double>(wanted->size() + 2)
                              : std::floor(planned_end * config.task.control_rate) + 1;
  check_motion_memory(name, poses, motion.body.voxel_cells.size());
  EvalResult result;
  for (int run = 0; run < 2; ++run) {
    NearestPoses keep(wanted);
    worker::EvaluateOptions options;
    options.ids = ids;
    options.on_start = [&motion](const worker::TraceHeader& h) {
      motion.terrain = h.model->terrain;
    };
    options.on_frame = [&keep](const worker::TraceFrame& frame) { keep.offer(pose_of(frame)); };
    result = worker::evaluate(config, *task, plan, controller, 0, options);
    motion.poses = keep.finish();
    if (!wanted || motion.poses.empty()) break;
    std::vector<double> again = request.shown_times(motion.poses.back().time);
    std::sort(again.begin(), again.end());
    std::vector<double> planned = *wanted;
    std::sort(planned.begin(), planned.end());
    if (again == planned) break;
    wanted = std::move(again);
  }
  if (motion.poses.empty()) {
    throw std::runtime_error("simulation of " + name + " recorded no frame: " +
                             (result.message.empty() ? to_string(result.status) : result.message));
  }
  char line[160];
  std::snprintf(line, sizeof line, "%s fitness %s, status %s, %.2f s simulated",
                to_string(config.task.kind), round_trip(result.fitness).c_str(),
                to_string(result.status), result.sim_seconds);
  motion.summary = line;
  motion.status = to_string(result.status);
  return motion;
}

// The ground of an evaluation of `plan` (work unit 0) under `config`, as the simulation lays it.
physics::Terrain ground_of(const Config& config, const BodyPlan& plan,
                           const worker::EvaluationIds& ids) {
  return physics::make_terrain(worker::terrain_params(config, ids, 0), plan.lattice,
                               static_cast<double>(static_cast<float>(plan.voxel_size)));
}

// The ground a trace recorded (docs/trace.md), rebuilt from its attributes.
physics::Terrain ground_of(const io::Trace& trace) {
  physics::Terrain t;
  if (!trace.terrain) return t;
  const io::Trace::Terrain& g = *trace.terrain;
  for (auto kind : {physics::TerrainKind::rows, physics::TerrainKind::bumps,
                    physics::TerrainKind::steps, physics::TerrainKind::slope})
    if (g.kind == softevo::to_string(kind)) t.kind = kind;
  if (t.kind == physics::TerrainKind::flat) return t;  // a kind this build does not know
  t.params.kind = t.kind;
  t.params.seed = std::strtoull(g.seed.c_str(), nullptr, 16);
  t.params.shape = g.shape;
  // make_terrain derives everything else from the lattice; a trace records the derived
  // positions instead, so set them over a layout for a one-cell lattice.
  t = physics::make_terrain(t.params, {1, 1, 1}, trace.voxel_size);
  t.start_x = g.bumps_start_x;
  t.first_riser_x = g.first_riser_x;
  t.start_d = g.slope_start;
  for (std::size_t r = 0; r < t.row_x.size() && r < g.row_x.size(); ++r) t.row_x[r] = g.row_x[r];
  if (t.kind == physics::TerrainKind::rows) {
    t.row_y_min = g.row_y_min - trace.voxel_size;
    t.row_y_max = g.row_y_max + trace.voxel_size;
  }
  return t;
}

Motion static_motion(const BodyPlan& plan, int material_count, const std::string& name) {
  Motion motion;
  motion.body = scene::body_from_plan(plan, material_count);
  motion.poses.push_back(scene::rest_pose(motion.body));
  motion.name = name;
  return motion;
}

// Body of a trace: voxels from the trace, chamber cells from a robot file when known.
scene::Body trace_body(const io::Trace& trace, const std::string& path,
                       const std::string& robot_file) {
  const auto voxels = static_cast<std::size_t>(trace.voxels);
  const auto cell = [&trace](std::size_t v) {
    return Eigen::Vector3i(trace.voxel_cells[3 * v], trace.voxel_cells[3 * v + 1],
                           trace.voxel_cells[3 * v + 2]);
  };
  std::optional<RobotFile> robot;
  if (!robot_file.empty()) {
    robot = read_robot_file(robot_file);
  } else if (!trace.robot_json.empty()) {
    robot = parse_robot_json(trace.robot_json, path + ":robot_json");
  }
  scene::Body body;
  if (robot) {
    body = scene::body_from_plan(robot->body);
    bool same = body.voxel_cells.size() == voxels;
    for (std::size_t v = 0; same && v < voxels; ++v) same = body.voxel_cells[v] == cell(v);
    if (!same) {
      throw std::runtime_error(path + ": the robot's voxels do not match the trace's voxel_cells");
    }
    body.voxel_size = trace.voxel_size;
    return body;
  }
  body.voxel_size = trace.voxel_size;
  for (std::size_t v = 0; v < voxels; ++v) {
    body.voxel_cells.push_back(cell(v));
    body.voxel_material.push_back(trace.voxel_material[v]);
    body.material_count = std::max(body.material_count, static_cast<int>(trace.voxel_material[v]));
  }
  return body;
}

Motion load_trace(const std::string& path, const MotionRequest& request) {
  const io::Trace trace = io::read_trace(path);
  Motion motion;
  motion.body = trace_body(trace, path, request.robot_file);
  motion.name = fs::path(path).stem().string();
  motion.direction_deg = trace.direction_deg;
  motion.terrain = ground_of(trace);
  const auto voxels = static_cast<std::size_t>(trace.voxels);
  const auto chambers = static_cast<std::size_t>(trace.chambers);
  std::optional<std::vector<double>> wanted;
  if (request.shown_times && trace.frames > 0) wanted = request.shown_times(trace.time.back());
  check_motion_memory(
      path, wanted ? static_cast<double>(wanted->size() + 2) : static_cast<double>(trace.frames),
      voxels);
  NearestPoses keep(wanted);
  for (std::size_t f = 0; f < static_cast<std::size_t>(trace.frames); ++f) {
    scene::Pose pose;
    pose.time = trace.time[f];
    pose.position.resize(voxels);
    pose.orientation.resize(voxels);
    for (std::size_t v = 0; v < voxels; ++v) {
      const double* p = &trace.positions[(f * voxels + v) * 3];
      const double* q = &trace.orientations[(f * voxels + v) * 4];
      pose.position[v] = Eigen::Vector3d(p[0], p[1], p[2]);
      pose.orientation[v] = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    }
    if (chambers > 0) {
      pose.chamber_pressure.assign(
          trace.pressures.begin() + static_cast<std::ptrdiff_t>(f * chambers),
          trace.pressures.begin() + static_cast<std::ptrdiff_t>((f + 1) * chambers));
    }
    keep.offer(std::move(pose));
  }
  motion.poses = keep.finish();
  if (motion.poses.empty()) throw std::runtime_error(path + ": trace has no frame");
  if (trace.fitness && !trace.status.empty()) {
    char line[160];
    std::snprintf(line, sizeof line, "traced fitness %s, status %s",
                  round_trip(*trace.fitness).c_str(), trace.status.c_str());
    motion.summary = line;
    motion.status = trace.status;
  }
  if (motion.body.chamber_cells.empty()) {
    motion.summary += std::string(motion.summary.empty() ? "" : "; ") +
                      "trace has no chamber cells (pass --robot ROBOT.json to draw them)";
  }
  return motion;
}

ArchivedIndividual individual_at(const io::GenerationRecord& record, std::size_t row,
                                 const std::string& path, const std::string& config_text,
                                 const Config& config, const std::string& experiment) {
  ArchivedIndividual ind;
  ind.archive_path = path;
  ind.config_text = config_text;
  ind.config = config;
  ind.experiment = experiment;
  ind.generation = record.generation;
  ind.id = record.id[row];
  ind.row = row;
  ind.status = record.status[row];
  ind.fitness = record.fitness[row];
  ind.voxels = record.voxels[row];
  ind.chambers = record.chambers[row];
  // In a learning run the archived fitness is the learned controller's (docs/model.md §8.11):
  // the robot that earned it is the body with that controller.
  ind.genome = record.has_learning() ? record.learned_genome[row] : record.genome[row];
  ind.units = record.units;
  ind.component_columns = record.component_columns;
  const std::size_t per_row =
      static_cast<std::size_t>(record.units) * record.component_columns.size();
  if (record.components.size() == per_row * record.size()) {
    ind.components.assign(
        record.components.begin() + static_cast<std::ptrdiff_t>(row * per_row),
        record.components.begin() + static_cast<std::ptrdiff_t>((row + 1) * per_row));
  }
  return ind;
}

}  // namespace

std::vector<std::int64_t> archived_generations(const std::string& archive_path) {
  const io::Archive archive(archive_path);
  return archive.generations();
}

std::vector<ArchivedIndividual> archived_generation(const std::string& archive_path,
                                                    std::optional<std::int64_t> generation) {
  const io::Archive archive(archive_path);
  const std::vector<std::int64_t> gens = archive.generations();
  if (gens.empty()) throw std::runtime_error(archive_path + ": archive has no generation yet");
  const std::int64_t g = generation ? *generation : gens.back();
  if (!std::binary_search(gens.begin(), gens.end(), g)) {
    throw std::runtime_error(archive_path + ": no generation " + std::to_string(g) +
                             " (archive has " + std::to_string(gens.front()) + ".." +
                             std::to_string(gens.back()) + ")");
  }
  const std::string config_text = archive.config_text();
  const Config config = parse_config(config_text, archive_path + ":/config");
  const std::string experiment = archive.info().experiment;
  const io::GenerationRecord record = archive.generation(g);
  record.check();
  std::vector<ArchivedIndividual> out;
  for (std::size_t row = 0; row < record.size(); ++row) {
    out.push_back(individual_at(record, row, archive_path, config_text, config, experiment));
  }
  return out;
}

ArchivedIndividual archived_individual(const std::string& archive_path,
                                       std::optional<std::int64_t> generation,
                                       std::optional<std::int64_t> id) {
  // With an id and no generation: the last generation that holds it (ArchiveError naming where
  // the id is when the generation given does not hold it).
  if (id) generation = io::Archive(archive_path).generation_of(*id, generation);
  std::vector<ArchivedIndividual> all = archived_generation(archive_path, generation);
  if (all.empty()) throw std::runtime_error(archive_path + ": generation has no individual");
  if (id) {
    for (auto& ind : all) {
      if (ind.id == *id) return std::move(ind);
    }
    throw std::runtime_error(archive_path + ": generation " + std::to_string(all[0].generation) +
                             " has no individual with id " + std::to_string(*id));
  }
  // Best: highest fitness, the lowest id on ties (rows are in id order).
  std::size_t best = 0;
  for (std::size_t i = 1; i < all.size(); ++i) {
    if (all[i].fitness > all[best].fitness) best = i;
  }
  return std::move(all[best]);
}

RobotFile robot_of(const ArchivedIndividual& individual) {
  const evo::Genome genome = evo::decode_genome(individual.genome);
  const std::string name = individual.experiment + " gen " + std::to_string(individual.generation) +
                           " id " + std::to_string(individual.id);
  const worker::BuiltRobot built =
      worker::build_robot(individual.config, genome, *tasks::make_task(individual.config));
  if (!built.valid || !built.actuatable) {
    throw std::runtime_error(individual.archive_path + ": individual " +
                             std::to_string(individual.id) + " of generation " +
                             std::to_string(individual.generation) + " has an invalid body (" +
                             (built.valid ? "no chamber" : "no structural voxel") + ")");
  }
  return worker::robot_file_of(individual.config, genome, name);
}

Motion load_motion(const std::string& input, const MotionRequest& request) {
  if (!fs::exists(input)) throw std::runtime_error(input + ": no such file");
  if (is_json(input)) {
    const RobotFile robot = read_robot_file(input);
    const std::string name = robot.name.empty() ? fs::path(input).stem().string() : robot.name;
    // As `softevo eval`: --config, else the robot file's run config, else the defaults.
    worker::RobotEvalSettings settings;
    settings.config_path = request.config_file;
    settings.overrides = request.overrides;
    const Config config = worker::robot_eval_config(robot, settings);
    if (!request.needs_motion || request.static_pose) {
      Motion still =
          static_motion(robot.body, static_cast<int>(config.physics.material_count), name);
      still.terrain = ground_of(config, robot.body, {});
      still.direction_deg = shown_direction(config, robot.controller, request);
      return still;
    }
    Motion motion = simulate_motion(config, robot.body, robot.controller, request, name);
    motion.summary += "; config: " + worker::describe_config_source(robot, settings);
    return motion;
  }
  if (io::is_run_archive(input)) {
    const ArchivedIndividual ind = archived_individual(input, request.generation, request.id);
    const RobotFile robot = robot_of(ind);
    const worker::EvaluationIds ids{ind.generation, ind.id};
    if (!request.needs_motion || request.static_pose) {
      Motion still = static_motion(robot.body, static_cast<int>(ind.config.physics.material_count),
                                   robot.name);
      still.terrain = ground_of(ind.config, robot.body, ids);
      still.direction_deg = shown_direction(ind.config, robot.controller, request);
      return still;
    }
    Motion motion =
        simulate_motion(ind.config, robot.body, robot.controller, request, robot.name, ids);
    char archived[96];
    std::snprintf(archived, sizeof archived, "; archived fitness %s",
                  round_trip(ind.fitness).c_str());
    motion.summary += archived;
    return motion;
  }
  if (io::is_trace(input)) return load_trace(input, request);
  // A file another process locks looks like no HDF5 file to libhdf5: say that instead.
  if (const std::optional<std::string> locked = io::locked_file_note(input))
    throw std::runtime_error(*locked);
  throw std::runtime_error(input +
                           ": neither a run archive (format softevo.run/1) nor a trace "
                           "(/positions); robot files must end in .json");
}

}  // namespace softevo::motion
