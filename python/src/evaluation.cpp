// Evaluation from Python: evaluate() (the path of `softevo eval`), the steppable Simulation and
// the robot's own controller. The GIL is released while the physics runs.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "physics/observables.hpp"
#include "physics/pneumatics.hpp"
#include "physics/state.hpp"
#include "physics/terrain.hpp"
#include "python/src/bindings.hpp"
#include "render/compose.hpp"
#include "render/render.hpp"
#include "scene/scene.hpp"
#include "tasks/task.hpp"
#include "worker/controller.hpp"
#include "worker/evaluate.hpp"
#include "worker/robot_eval_ids.hpp"
#include "worker/simulation.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace softevo::python {
namespace {

// An evaluation's result with the names of its task's components.
struct Result {
  EvalResult result;
  std::string task;
  std::string config_source;  // softevo::to_string(RobotConfigSource): robot, text or defaults
  std::vector<tasks::ComponentName> names;
};

// One unit's components: fitness, status and every named component.
py::dict unit_components(const Result& r, const UnitFitness& u) {
  py::dict d;
  d["fitness"] = u.fitness;
  d["status"] = std::string(to_string(u.status));
  for (std::size_t i = 0; i < r.names.size() && i < u.values.size(); ++i)
    d[py::str(r.names[i].name)] = u.values[i];
  return d;
}

struct Ablation {
  bool oscillator = false;
  bool sensors = false;
};

// None, "oscillator", "sensors" or a sequence of them.
Ablation parse_ablation(const py::object& ablate) {
  Ablation a;
  if (ablate.is_none()) return a;
  std::vector<std::string> names;
  if (py::isinstance<py::str>(ablate))
    names.push_back(ablate.cast<std::string>());
  else
    for (const py::handle item : ablate) names.push_back(py::str(item).cast<std::string>());
  for (const std::string& n : names) {
    if (n == "oscillator")
      a.oscillator = true;
    else if (n == "sensors")
      a.sensors = true;
    else
      throw py::value_error("ablate: '" + n + "' is not one of oscillator, sensors");
  }
  return a;
}

// How evaluate() and Simulation() resolve their config: as `softevo eval` does
// (worker::robot_eval_config); `config` None = the robot file's evaluation block (its run's
// config), else the built-in defaults.
worker::RobotEvalSettings eval_settings(const std::optional<Config>& config,
                                        const std::optional<std::string>& task,
                                        const std::optional<double>& seconds,
                                        const std::optional<std::string>& integrator,
                                        const std::optional<double>& direction) {
  worker::RobotEvalSettings s;
  if (config) s.config_text = canonical_text(*config);
  if (task) s.task = *task;
  if (seconds) {
    if (!(*seconds > 0.0) || !std::isfinite(*seconds))
      throw py::value_error("seconds: must be a positive number, got " + std::to_string(*seconds));
    s.seconds = *seconds;
  }
  if (integrator) {
    try {
      s.integrator = parse_choice<Integrator>(*integrator, "integrator");
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
  }
  if (direction) {
    if (!std::isfinite(*direction)) throw py::value_error("direction: must be finite");
    s.direction = *direction;
  }
  return s;
}

Result evaluate_robot(const RobotFile& robot, const std::optional<Config>& config,
                      const std::optional<std::string>& task, const std::optional<double>& seconds,
                      const std::optional<std::string>& integrator, const py::object& ablate,
                      const std::optional<double>& direction) {
  const worker::RobotEvalSettings settings =
      eval_settings(config, task, seconds, integrator, direction);
  const Config resolved = worker::robot_eval_config(robot, settings);
  const std::unique_ptr<tasks::Task> t = tasks::make_task(resolved);
  worker::EvaluateOptions opts;  // as `softevo eval`: the config's deadline, the best SIMD width
  opts.deadline = worker::deadline_after(resolved.run.eval_timeout_seconds);
  opts.ids = worker::robot_eval_ids(robot, settings);  // the ground its run gave it
  const Ablation a = parse_ablation(ablate);
  opts.ablate_oscillator = a.oscillator;
  opts.ablate_sensors = a.sensors;
  Result r;
  r.task = to_string(resolved.task.kind);
  r.config_source = softevo::to_string(worker::robot_config_source(robot, settings));
  r.names = t->component_names();
  // Ctrl-C: Python runs its SIGINT handler only when the interpreter gets control, which a
  // long evaluation without the GIL withholds (issue 29: 14 s). The evaluation asks at most
  // every kSignalCheckInterval, with the GIL, and stops when a handler raised.
  constexpr auto kSignalCheckInterval = std::chrono::milliseconds(50);
  bool interrupted = false;
  auto last_check = std::chrono::steady_clock::now();
  opts.abandon = [&] {
    const auto now = std::chrono::steady_clock::now();
    if (interrupted || now - last_check < kSignalCheckInterval) return interrupted;
    last_check = now;
    const py::gil_scoped_acquire locked;
    interrupted = PyErr_CheckSignals() != 0;  // the exception stays set for below
    return interrupted;
  };
  {
    const py::gil_scoped_release unlocked;
    r.result = worker::evaluate_all_units(resolved, *t, robot.body, robot.controller, opts);
  }
  if (interrupted) throw py::error_already_set();  // KeyboardInterrupt, as Python raised it
  return r;
}

// A float32 array of n values from a Python sequence or array (any shape with n elements).
std::vector<float> float_values(const py::handle& values, std::size_t n, const char* what) {
  const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a) throw py::value_error(std::string(what) + ": not convertible to a float array");
  if (static_cast<std::size_t>(a.size()) != n)
    throw py::value_error(std::string(what) + ": " + std::to_string(a.size()) +
                          " values, expected " + std::to_string(n));
  return std::vector<float>(a.data(), a.data() + n);
}

// 1 bar [Pa]: the observation's pressures are all given in Pa (SI); sensor_pressures keeps
// the controller's own scale (bar), which Controller.act reads.
constexpr double kPaPerBar = 1e5;

// The steppable simulation of one work unit, with its config and task.
class PySimulation {
 public:
  PySimulation(const RobotFile& robot, const std::optional<Config>& config,
               const std::optional<std::string>& task, const std::optional<double>& seconds,
               const std::optional<std::string>& integrator, const std::optional<double>& direction,
               int unit, bool observe_voxels)
      : config_(worker::robot_eval_config(
            robot, eval_settings(config, task, seconds, integrator, direction))),
        ids_(worker::robot_eval_ids(robot,
                                    eval_settings(config, task, seconds, integrator, direction))),
        task_(tasks::make_task(config_)),
        body_(robot.body),
        unit_(unit),
        observe_voxels_(observe_voxels) {
    start();
    if (sim_->status() == EvalStatus::invalid_body)
      throw py::value_error("Simulation: robot '" + robot.name + "': " + sim_->message());
  }

  py::dict reset() {
    start();
    return observation();
  }

  py::tuple step(const py::handle& valves) {
    if (!sim_->running())
      throw py::value_error("Simulation.step: the simulation has ended (status " +
                            std::string(to_string(sim_->status())) + ", frame " +
                            std::to_string(sim_->frame()) + " of " +
                            std::to_string(sim_->frames()) + "); call reset()");
    const std::vector<float> commands =
        float_values(valves, static_cast<std::size_t>(sim_->valve_count()), "valves");
    for (float c : commands)
      if (!(c >= 0.0f && c <= 1.0f))
        throw py::value_error("valves: openings must be in [0, 1], got " + std::to_string(c));
    {
      const py::gil_scoped_release unlocked;
      sim_->step(commands);
    }
    py::dict obs = observation();
    py::dict info;
    info["status"] = std::string(to_string(sim_->status()));
    info["frame"] = sim_->frame();
    info["steps"] = sim_->steps();
    info["message"] = sim_->message();
    return py::make_tuple(obs, info);
  }

  // The unit's result once, cached (the task scores the final state only once).
  Result result() {
    if (!result_) {
      Result r;
      r.task = to_string(config_.task.kind);
      r.names = task_->component_names();
      r.result = sim_->finish();
      worker::finalize_unit_result(*task_, r.result);
      result_ = std::move(r);
    }
    return *result_;
  }

  py::dict observation() {
    const physics::Model& model = sim_->model();
    const physics::State& state = sim_->state();
    const int chambers = sim_->chambers();
    std::vector<double> pressures(static_cast<std::size_t>(chambers));
    std::vector<float> sensors(static_cast<std::size_t>(chambers));
    for (int q = 0; q < chambers; ++q) {
      pressures[q] = physics::chamber_pressure_pa(sim_->pneumatics(), q);
      sensors[q] = sim_->sensor_pressure_bar(q);
    }
    // The task's inputs are read at the start of a frame; after the last one they stay those
    // of the last frame.
    if (sim_->running()) sim_->task_inputs(task_inputs_);
    const physics::Vec3 c = physics::centroid_displacement(model, state);
    py::dict obs;
    obs["frame"] = sim_->frame();
    obs["time"] = sim_->time();
    obs["pressures"] = array_of(pressures);
    obs["sensor_pressures"] = array_of(sensors);  // [bar]: kept, Controller.act reads it
    std::vector<double> sensors_pa(sensors.size());
    for (std::size_t q = 0; q < sensors.size(); ++q)
      sensors_pa[q] = kPaPerBar * static_cast<double>(sensors[q]);
    obs["sensor_pressures_pa"] = array_of(sensors_pa);
    obs["task_inputs"] = array_of(task_inputs_);
    obs["centroid"] = array_of(std::vector<double>{c.x(), c.y(), c.z()});
    obs["heading"] = physics::mean_rotation_vector(model, state).z();
    // Each task input under the task's own name (the directed task's direction_sensor).
    const std::vector<std::string> input_names = task_->controller_input_names();
    for (std::size_t i = 0; i < input_names.size() && i < task_inputs_.size(); ++i)
      obs[py::str(input_names[i])] = task_inputs_[i];
    // The task's score if the unit ended now: fitness and named components.
    const UnitFitness so_far = sim_->score_so_far();
    obs["fitness_so_far"] = so_far.fitness;
    py::dict components;
    const std::vector<tasks::ComponentName> names = task_->component_names();
    for (std::size_t i = 0; i < names.size() && i < so_far.values.size(); ++i)
      components[py::str(names[i].name)] = so_far.values[i];
    obs["components"] = components;
    if (observe_voxels_) {
      obs["positions"] = positions();
      obs["orientations"] = orientations();
    }
    return obs;
  }

  py::array_t<double> positions() const {
    const auto& pos = sim_->state().pos;
    py::array_t<double> a({static_cast<py::ssize_t>(pos.size()), py::ssize_t{3}});
    auto out = a.mutable_unchecked<2>();
    for (std::size_t v = 0; v < pos.size(); ++v)
      for (int i = 0; i < 3; ++i) out(v, i) = pos[v][i];
    return a;
  }

  py::array_t<double> orientations() const {
    const auto& q = sim_->state().orient;
    py::array_t<double> a({static_cast<py::ssize_t>(q.size()), py::ssize_t{4}});
    auto out = a.mutable_unchecked<2>();
    for (std::size_t v = 0; v < q.size(); ++v) {
      out(v, 0) = q[v].w;
      out(v, 1) = q[v].x;
      out(v, 2) = q[v].y;
      out(v, 3) = q[v].z;
    }
    return a;
  }

  // The current state drawn by the headless renderer of `softevo render` (render/render.hpp):
  // an RGB image (height, width, 3) of uint8, framed on the robot, the ground (terrain too)
  // under it. One pose, so rigid cubes at the voxels' positions and orientations.
  py::array_t<std::uint8_t> render(int width, int height, const std::string& view_name) const {
    if (width < 32 || width > 8192 || height < 32 || height > 8192)
      throw py::value_error("render: width and height must be in [32, 8192], got " +
                            std::to_string(width) + " x " + std::to_string(height));
    render::View view;
    try {
      view = render::parse_view(view_name);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(std::string("render: ") + e.what());
    }
    const scene::Body body =
        scene::body_from_plan(body_, static_cast<int>(config_.physics.material_count));
    scene::Pose pose;
    pose.time = sim_->time();
    for (const physics::Vec3& p : sim_->state().pos)
      pose.position.emplace_back(p.x(), p.y(), p.z());
    for (const auto& q : sim_->state().orient) pose.orientation.emplace_back(q.w, q.x, q.y, q.z);
    for (int q = 0; q < sim_->chambers(); ++q)
      pose.chamber_pressure.push_back(physics::chamber_pressure_pa(sim_->pneumatics(), q));
    const std::vector<scene::Pose> poses{pose};
    render::SceneOptions scene;
    scene.floor_z = -0.5 * body.voxel_size;
    const physics::Terrain& terrain = sim_->model().terrain;
    if (terrain.kind != physics::TerrainKind::flat) {
      // As `softevo render`: the surface half a voxel below where a voxel centre rests
      // (docs/model.md §2.8a), its height range sampled around the robot.
      const double half = 0.5 * body.voxel_size;
      scene.ground = [terrain, half](double x, double y) {
        return physics::terrain_height(terrain, x, y) - half;
      };
      const Eigen::AlignedBox3d box = render::pose_bounds(body, pose);
      double lo = scene.floor_z, hi = scene.floor_z;
      for (double x = box.min().x() - 0.3; x <= box.max().x() + 0.3; x += 0.004)
        for (double y = box.min().y() - 0.3; y <= box.max().y() + 0.3; y += 0.004) {
          lo = std::min(lo, scene.ground(x, y));
          hi = std::max(hi, scene.ground(x, y));
        }
      scene.ground_min = lo;
      scene.ground_max = hi;
    }
    render::Image image;
    {
      const py::gil_scoped_release unlocked;
      image = render::render_still(render::Clip{body, poses, ""}, view, pose.time, width, height,
                                   scene);
    }
    py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(image.height),
                                   static_cast<py::ssize_t>(image.width), py::ssize_t{3}});
    std::copy(image.rgb.begin(), image.rgb.end(), out.mutable_data());
    return out;
  }

  const worker::Simulation& sim() const { return *sim_; }
  void steer(double direction_deg) {
    try {
      sim_->steer(direction_deg);
    } catch (const std::logic_error& e) {  // std::invalid_argument included
      throw py::value_error(std::string("steer: ") + e.what());
    }
  }
  const Config& config() const { return config_; }

 private:
  void start() {
    result_.reset();
    sim_ = std::make_unique<worker::Simulation>(config_, *task_, body_, unit_, physics::Simd::best,
                                                ids_);
    task_inputs_.assign(static_cast<std::size_t>(task_->controller_inputs()), 0.0f);
  }

  Config config_;
  worker::EvaluationIds ids_;          // the ground of its run (worker::robot_eval_ids)
  std::unique_ptr<tasks::Task> task_;  // refers to config_
  BodyPlan body_;
  int unit_ = 0;
  bool observe_voxels_ = false;
  std::unique_ptr<worker::Simulation> sim_;  // refers to config_ and task_
  std::vector<float> task_inputs_;
  std::optional<Result> result_;
};

// The robot's own Elman controller, fed from Simulation observations.
class PyController {
 public:
  PyController(const RobotFile& robot, const std::optional<Config>& config,
               const py::object& ablate)
      : controller_(make(robot, config, ablate)) {}

  py::array_t<float> act(const py::dict& obs) {
    if (!obs.contains("task_inputs") || !obs.contains("sensor_pressures"))
      throw py::key_error(
          "Controller.act: the observation needs 'task_inputs' and 'sensor_pressures' (as "
          "Simulation.reset() and step() give them)");
    const auto task_inputs =
        py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(obs["task_inputs"]);
    const auto sensors = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(
        obs["sensor_pressures"]);
    if (!task_inputs || !sensors)
      throw py::value_error("Controller.act: 'task_inputs' and 'sensor_pressures' must be arrays");
    // A NaN or infinity would enter the recurrent state and stay there until reset(): refused,
    // naming the field (docs/guide.md, Python).
    const auto require_finite = [](const auto& a, const char* field) {
      for (py::ssize_t i = 0; i < a.size(); ++i)
        if (!std::isfinite(a.data()[i]))
          throw py::value_error(std::string("Controller.act: '") + field + "'[" +
                                std::to_string(i) + "] is not finite (" +
                                std::to_string(a.data()[i]) +
                                "); the controller's state is unchanged");
    };
    require_finite(task_inputs, "task_inputs");
    require_finite(sensors, "sensor_pressures");
    const std::size_t chambers = static_cast<std::size_t>(sensors.size());
    py::array_t<float> commands({static_cast<py::ssize_t>(chambers), py::ssize_t{2}});
    controller_.act({task_inputs.data(), static_cast<std::size_t>(task_inputs.size())},
                    {sensors.data(), chambers}, {commands.mutable_data(), 2 * chambers});
    return commands;
  }

  void reset() { controller_.reset(); }
  py::array_t<float> inputs() const {
    const auto in = controller_.inputs();
    return py::array_t<float>(static_cast<py::ssize_t>(in.size()), in.data());
  }

 private:
  static worker::ElmanController make(const RobotFile& robot, const std::optional<Config>& config,
                                      const py::object& ablate) {
    const Ablation a = parse_ablation(ablate);
    const double rate = config ? config->task.control_rate : Config{}.task.control_rate;
    return worker::ElmanController(robot.controller, rate, a.oscillator, a.sensors);
  }

  worker::ElmanController controller_;
};

}  // namespace

void bind_evaluation(py::module_& m) {
  py::class_<Result>(m, "EvalResult", "The result of an evaluation (all work units of the task).")
      .def_property_readonly(
          "fitness", [](const Result& r) { return r.result.fitness; },
          "Fitness (0 for any status but ok).")
      .def_property_readonly(
          "status", [](const Result& r) { return std::string(to_string(r.result.status)); },
          "ok, killed: flipped, killed: exploded, diverged, failed, timeout or "
          "invalid body.")
      .def_property_readonly(
          "killed", [](const Result& r) { return is_killed(r.result.status); },
          "True for any status but ok.")
      .def_property_readonly(
          "message", [](const Result& r) { return r.result.message; },
          "Why the status is not ok ('' when ok).")
      .def_property_readonly(
          "task", [](const Result& r) { return r.task; }, "The task evaluated.")
      .def_property_readonly(
          "config_source", [](const Result& r) { return r.config_source; },
          "Which config was used: 'text' (the config argument), 'robot' (the robot file's "
          "evaluation block: its run's config) or 'defaults' (the built-in thesis values).")
      .def_property_readonly(
          "component_names",
          [](const Result& r) {
            py::list l;
            for (const auto& n : r.names) l.append(py::make_tuple(n.name, n.unit));
            return l;
          },
          "The task's named components as (name, unit) pairs.")
      .def_property_readonly(
          "components",
          [](const Result& r) {
            py::list l;
            for (const UnitFitness& u : r.result.components) l.append(unit_components(r, u));
            return l;
          },
          "One dict per work unit: fitness, status and every named component.")
      .def_property_readonly(
          "steps", [](const Result& r) { return r.result.steps; }, "Physics steps simulated.")
      .def_property_readonly(
          "voxels", [](const Result& r) { return r.result.voxels; }, "Voxels.")
      .def_property_readonly(
          "chambers", [](const Result& r) { return r.result.chambers; }, "Chambers.")
      .def_property_readonly(
          "sim_seconds", [](const Result& r) { return r.result.sim_seconds; },
          "Simulated time [s], summed over the units.")
      .def_property_readonly(
          "wall_seconds", [](const Result& r) { return r.result.wall_seconds; },
          "Wall time of the evaluation [s].")
      .def("__repr__", [](const Result& r) {
        return "<softevo.EvalResult " + r.task + " fitness " +
               py::repr(py::float_(r.result.fitness)).cast<std::string>() + " (" +
               to_string(r.result.status) + ")>";
      });

  m.def("evaluate", &evaluate_robot, "robot"_a, "config"_a = py::none(), "task"_a = py::none(),
        "seconds"_a = py::none(), "integrator"_a = py::none(), "ablate"_a = py::none(),
        "direction"_a = py::none(),
        R"(Evaluate a robot and return an EvalResult (fitness, status, components, steps, ...).

The same code path as `softevo eval --json`, so the fitness bits are equal for equal inputs:
  config      a softevo.Config; None = the robot's evaluation block (the config of the run
              it was exported from, robot.evaluation) if it has one, else the built-in thesis
              defaults with task.control from the robot's controller; result.config_source
              says which
  task        'gait', 'directed' or 'rotate'; None = the config's, or (no config) the task the
              controller's inputs fit
  seconds     simulated seconds (None = task.eval_seconds)
  integrator  'pneuvox' or 'symplectic' (None = the config's)
  ablate      None, 'oscillator', 'sensors' or a list of them: feed 0 to those inputs
  direction   directed task: evaluate this target direction [deg] alone
The GIL is released while the robot is simulated, so threads evaluate robots in parallel.
Bad input raises ValueError (ConfigError for a bad config key).)");

  py::tuple task_names(task_kinds().size());
  for (std::size_t i = 0; i < task_kinds().size(); ++i) task_names[i] = to_string(task_kinds()[i]);
  m.attr("TASKS") = task_names;

  py::class_<PySimulation>(m, "Simulation",
                           R"(One work unit of a task, stepped one 60 Hz control frame at a time.

    sim = softevo.Simulation(robot, config=None, task=None, seconds=None, integrator=None,
                             direction=None, unit=0, observe_voxels=False)
    obs = sim.reset()
    obs, info = sim.step(valves)     # valves: (chambers, 2) openings in [0, 1], inlet/outlet

The config is resolved as in softevo.evaluate(). An observation is a dict: frame, time [s],
pressures (chamber pressures, absolute [Pa]), sensor_pressures_pa (what a controller reads this
frame, absolute [Pa]; frame 0 reads pneumatics.initial_sensor_pressure): every pressure in Pa.
sensor_pressures keeps its earlier meaning, the same reading in the controller's own scale
[bar] as float32 (what Controller.act reads). task_inputs (the task's controller inputs),
centroid (centroid displacement since the start [m]), heading (mean rotation about z [rad]),
each task input under its name (direction_sensor of the directed task), fitness_so_far and
components (name -> value): the task's score if the unit ended now, and with observe_voxels
positions (n, 3) [m] and orientations (n, 4) (w, x, y, z). steer(direction) gives a steerable
task (directed) a new target direction [deg] for the sensor and the score. Feeding step() the commands of softevo.Controller(robot).act(obs) gives the
bits of softevo.evaluate() for that unit; result() scores it.)")
      .def(py::init<const RobotFile&, const std::optional<Config>&,
                    const std::optional<std::string>&, const std::optional<double>&,
                    const std::optional<std::string>&, const std::optional<double>&, int, bool>(),
           "robot"_a, "config"_a = py::none(), "task"_a = py::none(), "seconds"_a = py::none(),
           "integrator"_a = py::none(), "direction"_a = py::none(), "unit"_a = 0,
           "observe_voxels"_a = false)
      .def("reset", &PySimulation::reset,
           "Back to the initial state; returns the first observation.")
      .def("step", &PySimulation::step, "valves"_a,
           "Simulate one control frame with these valve openings ((chambers, 2) or 2 x chambers "
           "values in [0, 1]); returns (observation, info). The GIL is released meanwhile.")
      .def("result", &PySimulation::result,
           "The unit's EvalResult: the task's score of the current state when the status is ok.")
      .def(
          "state_hash", [](const PySimulation& s) { return physics::state_hash(s.sim().state()); },
          "Hash of the physics state (equal states, equal hashes).")
      .def("observation", &PySimulation::observation, "The current observation (as step gives).")
      .def("steer", &PySimulation::steer, "direction"_a,
           "A new target direction [deg, -180..180] from the next frame on, for the task's "
           "sensor and its score (steerable tasks only: directed); ValueError otherwise.")
      .def("positions", &PySimulation::positions, "Voxel centres (n, 3) [m].")
      .def("render", &PySimulation::render, "width"_a = 480, "height"_a = 360, "view"_a = "side",
           "The current state as an RGB image (height, width, 3) uint8, drawn by the headless "
           "renderer of `softevo render` (view: side, top or iso; the ground and any terrain "
           "under the robot).")
      .def("orientations", &PySimulation::orientations, "Voxel orientations (n, 4), (w, x, y, z).")
      .def_property_readonly(
          "time", [](const PySimulation& s) { return s.sim().time(); }, "Simulated time [s].")
      .def_property_readonly(
          "frame", [](const PySimulation& s) { return s.sim().frame(); },
          "Control frames simulated.")
      .def_property_readonly(
          "frames", [](const PySimulation& s) { return s.sim().frames(); },
          "Control frames of a full evaluation.")
      .def_property_readonly(
          "status", [](const PySimulation& s) { return std::string(to_string(s.sim().status())); },
          "ok until the robot is killed or diverges.")
      .def_property_readonly(
          "done", [](const PySimulation& s) { return !s.sim().running(); },
          "True when every frame ran or the status is not ok.")
      .def_property_readonly(
          "chambers", [](const PySimulation& s) { return s.sim().chambers(); }, "Chambers.")
      .def_property_readonly(
          "voxels", [](const PySimulation& s) { return s.sim().voxels(); }, "Voxels.")
      .def_property_readonly(
          "steps", [](const PySimulation& s) { return s.sim().steps(); }, "Physics steps so far.")
      .def_property_readonly(
          "steps_per_frame", [](const PySimulation& s) { return s.sim().steps_per_frame(); },
          "Physics steps per control frame.")
      .def_property_readonly(
          "control_rate", [](const PySimulation& s) { return s.config().task.control_rate; },
          "Control frames per simulated second [Hz].")
      .def_property_readonly("config", &PySimulation::config, "The resolved config.")
      .def_property_readonly(
          "task",
          [](const PySimulation& s) { return std::string(to_string(s.config().task.kind)); },
          "The task.");

  py::class_<PyController>(m, "Controller",
                           R"(The robot's own Elman controller (docs/model.md §4) as a policy.

    controller = softevo.Controller(robot, config=None, ablate=None)
    valves = controller.act(obs)    # (chambers, 2) float32 openings for Simulation.step

It keeps its oscillator phase and context units between calls; reset() starts it again.)")
      .def(py::init<const RobotFile&, const std::optional<Config>&, const py::object&>(), "robot"_a,
           "config"_a = py::none(), "ablate"_a = py::none())
      .def("act", &PyController::act, "obs"_a,
           "Valve commands for the observation of this frame (uses task_inputs and "
           "sensor_pressures).")
      .def("reset", &PyController::reset, "Back to the state before the first frame.")
      .def_property_readonly("inputs", &PyController::inputs,
                             "The network inputs of the last act() (float32).");
}

}  // namespace softevo::python
