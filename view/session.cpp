// See session.hpp.
#include "view/session.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "io/archive.hpp"
#include "io/run_lock.hpp"
#include "io/trace.hpp"
#include "motion/trace_recorder.hpp"
#include "physics/observables.hpp"
#include "physics/pneumatics.hpp"
#include "tasks/task.hpp"
#include "worker/controller.hpp"
#include "worker/evaluate.hpp"
#include "worker/simulation.hpp"

namespace softevo::view {

namespace fs = std::filesystem;

namespace {

constexpr const char* kSteeringFormat = "softevo.steering/1";
constexpr float kQuatScale = 32767.0f;

bool has_extension(const std::string& path, const std::string& ext) {
  std::string e = fs::path(path).extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e == ext;
}

std::int16_t quantised(double unit_value) {
  return static_cast<std::int16_t>(std::lround(std::clamp(unit_value, -1.0, 1.0) * kQuatScale));
}

// Positions and orientations of voxels and chamber cells in the record's compact form.
void fill_pose(const scene::Body& body, const scene::Pose& pose, FrameRecord& r) {
  std::vector<Eigen::Vector3d> chamber_pos;
  std::vector<Eigen::Quaterniond> chamber_rot;
  if (!body.chamber_cells.empty())
    render::place_chamber_cells(body, pose, chamber_pos, chamber_rot);
  const std::size_t items = pose.position.size() + chamber_pos.size();
  r.positions.clear();
  r.orientations.clear();
  r.positions.reserve(3 * items);
  r.orientations.reserve(4 * items);
  auto add = [&r](const Eigen::Vector3d& p, const Eigen::Quaterniond& q0) {
    const Eigen::Quaterniond q = q0.normalized();
    for (int i = 0; i < 3; ++i) r.positions.push_back(static_cast<float>(p[i]));
    for (double c : {q.w(), q.x(), q.y(), q.z()}) r.orientations.push_back(quantised(c));
  };
  for (std::size_t v = 0; v < pose.position.size(); ++v) add(pose.position[v], pose.orientation[v]);
  for (std::size_t j = 0; j < chamber_pos.size(); ++j) add(chamber_pos[j], chamber_rot[j]);
}

}  // namespace

ViewInput load_view_input(const std::string& path, const ViewRequest& request) {
  if (!fs::exists(path)) throw std::runtime_error(path + ": no such file");
  ViewInput in;
  if (has_extension(path, ".json")) {
    in.kind = InputKind::robot;
    in.robot = read_robot_file(path);
    in.name = in.robot.name.empty() ? fs::path(path).stem().string() : in.robot.name;
    worker::RobotEvalSettings settings;
    settings.config_path = request.config_file;
    settings.overrides = request.overrides;
    settings.task = request.task;
    settings.seconds = request.seconds;
    settings.direction = request.direction_deg;
    in.config = worker::robot_eval_config(in.robot, settings);
  } else if (io::is_run_archive(path)) {
    if (!request.task.empty() || !request.config_file.empty() || !request.overrides.empty())
      throw std::invalid_argument(path +
                                  ": an archived individual is simulated with the run's own "
                                  "config; --config, --set and --task are for robot files");
    in.kind = InputKind::archive;
    in.archived = motion::archived_individual(path, request.generation, request.id);
    in.robot = motion::robot_of(*in.archived);
    in.name = in.robot.name;
    in.config = in.archived->config;
    std::vector<std::string> overrides;
    if (request.seconds) overrides.push_back("task.eval_seconds=" + toml_number(*request.seconds));
    if (!overrides.empty()) in.config = apply_overrides(in.config, overrides);
  } else if (io::is_trace(path)) {
    in.kind = InputKind::trace;
    motion::MotionRequest mr;
    mr.robot_file = request.robot_file;
    in.trace_motion = motion::load_motion(path, mr);
    const io::Trace trace = io::read_trace(path);
    in.trace_valves = trace.valve_commands;
    in.trace_fitness = trace.fitness;
    in.trace_status = trace.status;
    in.name = in.trace_motion.name;
    in.body = in.trace_motion.body;
    in.config.task.control_rate = trace.frame_rate > 0.0 ? trace.frame_rate : 60.0;
    if (trace.direction_deg) {
      // A trace records no task, only a target direction, which the directed task alone has;
      // its replay is then that task's (steerable, direction sensor), asked of its module.
      in.config.task.kind = TaskKind::directed;
      in.config.task.directions = {*trace.direction_deg};
    }
    return in;
  } else {
    // A file another process locks looks like no HDF5 file to libhdf5: say that instead.
    if (const std::optional<std::string> locked = io::locked_file_note(path))
      throw std::runtime_error(*locked);
    throw std::runtime_error(path +
                             ": neither a robot file (.json), a run archive (format "
                             "softevo.run/1) nor a trace (/positions)");
  }
  in.body =
      scene::body_from_plan(in.robot.body, static_cast<int>(in.config.physics.material_count));
  return in;
}

std::string steering_log_json(const std::vector<SteerCommand>& log, const std::string& input_name) {
  nlohmann::json j;
  j["format"] = kSteeringFormat;
  j["input"] = input_name;
  j["commands"] = nlohmann::json::array();
  for (const auto& c : log) j["commands"].push_back({c.frame, c.direction_deg});
  return j.dump(1) + "\n";
}

std::vector<SteerCommand> parse_steering_log(const std::string& text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(source + ": not JSON (" + e.what() + ")");
  }
  if (!j.is_object() || j.value("format", "") != kSteeringFormat)
    throw std::invalid_argument(source + ": format must be \"" + kSteeringFormat + "\"");
  if (!j.contains("commands") || !j["commands"].is_array())
    throw std::invalid_argument(source + ": key commands must be an array of [frame, degrees]");
  std::vector<SteerCommand> log;
  for (const auto& c : j["commands"]) {
    const std::string where = source + ": commands[" + std::to_string(log.size()) + "]";
    if (!c.is_array() || c.size() != 2 || !c[0].is_number_integer() || !c[1].is_number())
      throw std::invalid_argument(where + " must be [frame (integer), degrees (number)]");
    const std::int64_t frame = c[0].get<std::int64_t>();
    const double deg = c[1].get<double>();
    if (frame < 0 || frame > std::numeric_limits<int>::max())
      throw std::invalid_argument(where + ": frame out of range");
    if (!log.empty() && frame < log.back().frame)
      throw std::invalid_argument(where + ": frames must be ascending");
    if (!std::isfinite(deg) || deg < -180.0 || deg > 180.0)
      throw std::invalid_argument(where + ": direction must be within [-180, 180] degrees");
    log.push_back({static_cast<int>(frame), deg});
  }
  return log;
}

std::string steering_log_path(const std::string& trace_path) {
  fs::path p(trace_path);
  p.replace_extension(".steering.json");
  return p.string();
}

// The simulation side of a live session.
struct Session::Live {
  Config config;
  std::unique_ptr<tasks::Task> task;
  std::unique_ptr<worker::Simulation> sim;
  std::unique_ptr<worker::ElmanController> brain;
  motion::TraceRecorder recorder;
  worker::EvaluateOptions recorder_hooks;
  std::vector<float> task_inputs, sensor_bar, commands;
  std::vector<double> pressures_pa;
};

Session::Session(const ViewInput& input, std::vector<SteerCommand> steering)
    : input_(input), steering_(std::move(steering)) {
  for (std::size_t i = 1; i < steering_.size(); ++i)
    if (steering_[i].frame < steering_[i - 1].frame)
      throw std::invalid_argument("steering log: frames must be ascending");
  if (!input_.live()) {
    if (!steering_.empty()) throw std::invalid_argument("a trace cannot be steered");
    planned_ = static_cast<int>(input_.trace_motion.poses.size());
    append_trace_record(0);
    return;
  }
  if (!steering_.empty() && !steerable())
    throw std::invalid_argument(input_.name + ": only a directed robot can be steered");
  live_ = std::make_unique<Live>();
  Live& l = *live_;
  l.config = input_.config;
  l.task = tasks::make_task(l.config);
  motion::check_trace_memory("(view session)", l.config, input_.robot.body);
  l.sim = std::make_unique<worker::Simulation>(l.config, *l.task, input_.robot.body, 0);
  if (l.sim->status() == EvalStatus::invalid_body)
    throw std::invalid_argument(input_.name + ": " + l.sim->message());
  l.brain = std::make_unique<worker::ElmanController>(input_.robot.controller,
                                                      l.config.task.control_rate);
  l.brain->check_chambers(l.sim->chambers());
  l.task_inputs.assign(static_cast<std::size_t>(l.task->controller_inputs()), 0.0f);
  l.sensor_bar.assign(static_cast<std::size_t>(l.sim->chambers()), 0.0f);
  l.commands.assign(static_cast<std::size_t>(l.sim->valve_count()), 1.0f);
  l.pressures_pa.assign(static_cast<std::size_t>(l.sim->chambers()), 0.0);
  if (l.task->steerable()) target_deg_ = l.config.task.directions.at(0);
  planned_ = l.sim->frames() + 1;
  l.recorder.attach(l.recorder_hooks);
  worker::TraceHeader h;
  h.model = &l.sim->model();
  h.chambers = l.sim->chambers();
  h.frames = l.sim->frames();
  h.steps_per_frame = l.sim->steps_per_frame();
  l.recorder_hooks.on_start(h);
  // Frame 0's record: the start pose with the commands of frame 0, as evaluate records it.
  advance();
}

Session::~Session() = default;

bool Session::steerable() const {
  return tasks::make_task(input_.config)->steerable();
}

double Session::control_rate() const {
  return input_.config.task.control_rate;
}

std::vector<std::string> Session::component_names() const {
  std::vector<std::string> names;
  if (live_) {
    for (const auto& c : live_->task->component_names()) names.push_back(c.name);
  }
  return names;
}

std::vector<std::string> Session::component_units() const {
  std::vector<std::string> units;
  if (live_) {
    for (const auto& c : live_->task->component_names()) units.push_back(c.unit);
  }
  return units;
}

std::string Session::fitness_unit() const {
  return live_ ? live_->task->fitness_unit() : tasks::make_task(input_.config)->fitness_unit();
}

const physics::Terrain& Session::terrain() const {
  return live_ ? live_->sim->model().terrain : input_.trace_motion.terrain;
}

bool TerrainGrid::covers(double x, double y, double margin) const {
  if (nx < 2 || ny < 2) return false;
  return x >= x0 + margin && x <= x0 + (nx - 1) * step - margin && y >= y0 + margin &&
         y <= y0 + (ny - 1) * step - margin;
}

std::array<double, 2> record_centre(const FrameRecord& record) {
  const std::vector<float>& p = record.positions;
  const std::size_t items = p.size() / 3;
  double cx = 0.0, cy = 0.0;
  for (std::size_t i = 0; i < items; ++i) cx += p[3 * i], cy += p[3 * i + 1];
  if (items > 0) cx /= static_cast<double>(items), cy /= static_cast<double>(items);
  return {cx, cy};
}

TerrainGrid terrain_grid(const Session& session, double margin) {
  const physics::Terrain& terrain = session.terrain();
  TerrainGrid g;
  if (terrain.kind == physics::TerrainKind::flat || session.records() == 0) return g;
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x;
  double hi_x = -lo_x, hi_y = -lo_x;
  for (int r = 0; r < session.records(); ++r) {
    const auto [x, y] = record_centre(session.record(r));
    lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
    lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
  }
  // The grid's size follows from the path: a path that is not finite (or beyond any ground a
  // simulation lays) would ask for a grid of any size (issue 39: "vector::reserve").
  constexpr double kFar = io::TraceLimits::position_m;
  if (!(lo_x >= -kFar && lo_y >= -kFar && hi_x <= kFar && hi_y <= kFar))
    throw std::runtime_error(
        "the robot's path leaves the ground's range (|x|, |y| <= 10 km) or "
        "is not finite: no ground can be drawn under it");
  lo_x -= margin, lo_y -= margin, hi_x += margin, hi_y += margin;
  const double s = session.input().body.voxel_size;
  g.kind = softevo::to_string(terrain.kind);
  // Two samples of the side are spent on snapping both ends outwards to the lattice.
  g.step = std::max(s, std::max(hi_x - lo_x, hi_y - lo_y) / (kTerrainGridMaxSide - 3));
  const double first_i = std::floor(lo_x / g.step), first_j = std::floor(lo_y / g.step);
  g.nx = static_cast<int>(std::ceil(hi_x / g.step) - first_i) + 1;
  g.ny = static_cast<int>(std::ceil(hi_y / g.step) - first_j) + 1;
  g.x0 = first_i * g.step;
  g.y0 = first_j * g.step;
  g.z.reserve(static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny));
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      g.z.push_back(static_cast<float>(
          physics::terrain_height(terrain, g.x0 + i * g.step, g.y0 + j * g.step) - 0.5 * s));
  return g;
}

std::optional<TerrainGrid> terrain_update(const Session& session, const TerrainGrid& shown,
                                          int record, double margin) {
  if (session.terrain().kind == physics::TerrainKind::flat) return std::nullopt;
  const auto [x, y] = record_centre(session.record(record));
  if (shown.covers(x, y, 0.5 * margin)) return std::nullopt;
  return terrain_grid(session, margin);
}

bool Session::finished() const {
  if (!live_) return true;
  return result_.has_value();
}

EvalStatus Session::status() const {
  if (result_) return result_->status;
  if (live_) return live_->sim->status();
  return EvalStatus::ok;
}

std::string Session::status_message() const {
  if (result_) return result_->message;
  if (live_) return live_->sim->message();
  return input_.trace_status;
}

void Session::steer(double direction_deg) {
  if (!live_ || !steerable()) throw std::logic_error("only a live directed robot can be steered");
  if (finished()) throw std::logic_error("the simulation has ended; reset to steer again");
  if (!std::isfinite(direction_deg) || direction_deg < -180.0 || direction_deg > 180.0)
    throw std::invalid_argument("steering direction must be within [-180, 180] degrees");
  // The next frame to simulate is the frame of the last record (its commands not yet stepped).
  const int frame = live_->sim->frame() + 1;
  if (!steering_.empty() && steering_.back().frame == frame)
    steering_.back().direction_deg = direction_deg;
  else
    steering_.push_back({frame, direction_deg});
}

bool Session::advance() {
  if (!live_ || result_) return false;
  Live& l = *live_;
  worker::Simulation& sim = *l.sim;
  if (!timeline_.empty()) {
    // 3-5. Kill checks, the task's observation, the physics of the frame whose record is last.
    sim.step(l.commands);
  }
  if (!sim.running()) {
    EvalResult r = sim.finish();
    worker::finalize_unit_result(*l.task, r);
    result_ = std::move(r);
    if (sim.status() == EvalStatus::ok) append_live_record(sim.frames());
    return false;
  }
  // 1-2. What the controller senses; a steering command hands the task its new target.
  while (next_command_ < steering_.size() && steering_[next_command_].frame <= sim.frame()) {
    target_deg_ = steering_[next_command_].direction_deg;
    sim.steer(target_deg_);
    ++next_command_;
  }
  sim.task_inputs(l.task_inputs);
  for (int q = 0; q < sim.chambers(); ++q) l.sensor_bar[q] = sim.sensor_pressure_bar(q);
  l.brain->act(l.task_inputs, l.sensor_bar, l.commands);
  append_live_record(sim.frame());
  return true;
}

void Session::append_live_record(int frame) {
  Live& l = *live_;
  const worker::Simulation& sim = *l.sim;
  for (int q = 0; q < sim.chambers(); ++q)
    l.pressures_pa[q] = physics::chamber_pressure_pa(sim.pneumatics(), q);
  worker::TraceFrame tf;
  tf.frame = frame;
  tf.time = sim.time();
  tf.positions = sim.state().pos;
  tf.orientations = sim.state().orient;
  tf.pressures = l.pressures_pa;
  tf.valve_commands = l.commands;
  tf.inputs = l.brain->inputs();
  l.recorder_hooks.on_frame(tf);

  FrameRecord r;
  r.frame = frame;
  r.time = sim.time();
  scene::Pose pose;
  pose.position.assign(sim.state().pos.begin(), sim.state().pos.end());
  pose.orientation.reserve(sim.state().orient.size());
  for (const auto& q : sim.state().orient) pose.orientation.emplace_back(q.w, q.x, q.y, q.z);
  fill_pose(input_.body, pose, r);
  r.pressures_pa.assign(l.pressures_pa.begin(), l.pressures_pa.end());
  r.valves = l.commands;
  const Eigen::Vector3d c = physics::centroid_displacement(sim.model(), sim.state());
  r.centroid_x = static_cast<float>(c.x());
  r.centroid_y = static_cast<float>(c.y());
  r.heading_rad = static_cast<float>(physics::mean_rotation_vector(sim.model(), sim.state()).z());
  r.target_deg = static_cast<float>(target_deg_);
  // Fitness components so far: the task's score of this record's state (the final result once
  // the unit has ended).
  const std::size_t n = l.task->component_names().size();
  UnitFitness so_far;
  if (result_ && !result_->components.empty()) {
    so_far = result_->components[0];
    so_far.fitness = result_->fitness;
  } else {
    so_far = sim.score_so_far();
  }
  r.components.assign(n, 0.0f);
  for (std::size_t i = 0; i < n && i < so_far.values.size(); ++i)
    r.components[i] = static_cast<float>(so_far.values[i]);
  r.fitness = static_cast<float>(so_far.fitness);
  timeline_.push_back(std::move(r));
}

void Session::append_trace_record(int index) {
  const motion::Motion& m = input_.trace_motion;
  for (int i = index; i < static_cast<int>(m.poses.size()); ++i) {
    const scene::Pose& pose = m.poses[static_cast<std::size_t>(i)];
    FrameRecord r;
    r.frame = i;
    r.time = pose.time;
    fill_pose(input_.body, pose, r);
    r.pressures_pa.assign(pose.chamber_pressure.begin(), pose.chamber_pressure.end());
    const std::size_t valves = 2 * pose.chamber_pressure.size();
    if (input_.trace_valves.size() >= (static_cast<std::size_t>(i) + 1) * valves && valves > 0)
      r.valves.assign(input_.trace_valves.begin() + static_cast<std::ptrdiff_t>(i * valves),
                      input_.trace_valves.begin() + static_cast<std::ptrdiff_t>((i + 1) * valves));
    const Eigen::Vector3d c0 = scene::centroid(m.poses.front()), c = scene::centroid(pose);
    r.centroid_x = static_cast<float>(c.x() - c0.x());
    r.centroid_y = static_cast<float>(c.y() - c0.y());
    r.target_deg = static_cast<float>(m.direction_deg.value_or(0.0));
    if (i + 1 == static_cast<int>(m.poses.size()) && input_.trace_fitness)
      r.fitness = static_cast<float>(*input_.trace_fitness);
    timeline_.push_back(std::move(r));
  }
}

void Session::save(const std::string& trace_path, Overwrite overwrite) const {
  if (!live_ || !result_) throw std::logic_error("a session is saved when its simulation ended");
  // The unit's configured direction (a steered run's targets are in its steering log).
  const std::optional<double> direction =
      steerable() ? std::optional<double>(live_->config.task.directions.at(0)) : std::nullopt;
  check_output_target(steering_log_path(trace_path), overwrite);
  live_->recorder.write(trace_path, input_.robot, *result_, control_rate(), direction, overwrite);
  write_file_atomically(steering_log_path(trace_path), steering_log_json(steering_, input_.name),
                        overwrite);
}

}  // namespace softevo::view
