// Robots (softevo.robot/1 files), configs and the development of a body from its CPPN.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "common/safe_write.hpp"
#include "evo/cppn.hpp"
#include "evo/development.hpp"
#include "evo/genome.hpp"
#include "fabricate/fabricate.hpp"
#include "io/archive.hpp"
#include "python/src/bindings.hpp"
#include "worker/evaluate.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace softevo::python {
namespace {

int voxel_count(const BodyPlan& body) {
  int n = 0;
  for (int v : body.cells) n += BodyPlan::is_structural(v) ? 1 : 0;  // chamber cells are air
  return n;
}

// The controller's 9 vectors (§4.4) one after the other, in canonical order.
py::array_t<double> controller_parameters(const RobotFile& robot) {
  std::vector<double> flat;
  for (const std::vector<double>* v : evo::vectors_of(robot.controller.vectors))
    flat.insert(flat.end(), v->begin(), v->end());
  return py::array_t<double>(static_cast<py::ssize_t>(flat.size()), flat.data());
}

RobotFile with_controller_parameters(const RobotFile& robot, const py::array_t<double>& values) {
  const py::buffer_info in = values.request();
  if (in.ndim != 1)
    throw py::value_error("controller parameters: a 1-D array is needed, got " +
                          std::to_string(in.ndim) + " dimensions");
  RobotFile out = robot;
  std::size_t expected = 0;
  for (const std::vector<double>* v : evo::vectors_of(out.controller.vectors))
    expected += v->size();
  if (static_cast<std::size_t>(in.size) != expected)
    throw py::value_error("controller parameters: " + std::to_string(in.size) +
                          " values, the controller of robot '" + robot.name + "' has " +
                          std::to_string(expected));
  const auto view = values.unchecked<1>();
  py::ssize_t i = 0;
  for (std::vector<double>* v : evo::vectors_of(out.controller.vectors))
    for (double& x : *v) x = view(i++);
  return out;
}

py::array_t<std::int32_t> cells_array(const BodyPlan& body) {
  const std::vector<py::ssize_t> shape{body.lattice[0], body.lattice[1], body.lattice[2]};
  py::array_t<std::int32_t> a(shape);
  auto out = a.mutable_unchecked<3>();
  for (int x = 0; x < body.lattice[0]; ++x)
    for (int y = 0; y < body.lattice[1]; ++y)
      for (int z = 0; z < body.lattice[2]; ++z) out(x, y, z) = body.cell(x, y, z);
  return a;
}

// §6 development of a robot file's CPPN: with `config`, its [body] settings and materials; else
// the settings the file's genome section records and the thesis materials (as `softevo develop`).
RobotFile develop_robot(const RobotFile& robot, const std::optional<Config>& config) {
  if (!robot.genome)
    throw py::value_error("develop: robot '" + robot.name +
                          "' has no \"genome\" section to develop a body from");
  const RobotGenomeRecord& rec = *robot.genome;
  const evo::CppnGenome cppn = evo::cppn_from_records(rec.nodes, rec.connections);
  BodyConfig body_config;
  PhysicsConfig physics;
  if (config) {
    body_config = config->body;
    physics = config->physics;
  } else {
    body_config.lattice.assign(rec.body_lattice.begin(), rec.body_lattice.end());
    body_config.distance_input = rec.distance_input;
  }
  evo::DevelopedBody developed = evo::develop_body(cppn, body_config);
  RobotFile out = robot;
  out.body = std::move(developed.plan);
  out.body.materials = material_table(physics);
  out.body.voxel_size = physics.voxel_size;
  return out;
}

// An encoded genome (as archived) developed and given its controller, as a run does.
RobotFile develop_genome(const py::bytes& encoded, const Config& config) {
  const std::string bytes = encoded;
  const std::vector<std::uint8_t> data(bytes.begin(), bytes.end());
  return worker::robot_file_of(config, evo::decode_genome(data), "");
}

// fabricate/ words its messages for `softevo fabricate`; Robot.fabricate's say its keyword
// arguments instead ("channel_diameter 1.5 mm is not narrower ...", "pass force=True"), as
// Python's evolve and config messages do. An option is replaced only as a word of its own (after
// the start, a space, '(' or ','), so a path that contains "--scale" keeps it.
std::string with_python_argument_names(const std::string& message) {
  static constexpr std::pair<std::string_view, std::string_view> kNames[] = {
      {"--channel-diameter", "channel_diameter"},
      {"--layer-um", "layer_um"},
      {"--scale", "scale"},
      {"--wall", "wall"},
      {"--dpi", "dpi"},
      {"--split", "split"},
      {"--slices", "slices"},
      {"--mold", "mold"},
      {"--format", "format"},
      {"--force", "force=True"},
      {"-o", "path"},
  };
  std::string out;
  std::size_t i = 0;
  if (message.rfind("fabricate: ", 0) == 0) {
    out = "Robot.fabricate: ";
    i = std::string_view("fabricate: ").size();
  }
  while (i < message.size()) {
    const bool word_start =
        i == 0 || message[i - 1] == ' ' || message[i - 1] == '(' || message[i - 1] == ',';
    bool replaced = false;
    if (word_start && message[i] == '-') {
      for (const auto& [cli, python] : kNames) {
        const std::size_t end = i + cli.size();
        const bool word_end = end == message.size() || message[end] == ' ' || message[end] == ')' ||
                              message[end] == ',' || message[end] == ':';
        if (message.compare(i, cli.size(), cli) == 0 && word_end) {
          out += python;
          i = end;
          replaced = true;
          break;
        }
      }
    }
    if (!replaced) out += message[i++];
  }
  return out;
}

// Robot.fabricate (softevo/__init__.py checks the keyword names and the units are the CLI's).
py::dict fabricate_robot(const RobotFile& robot, const std::string& output,
                         const std::string& format, double scale, double channel_diameter_mm,
                         const std::string& slices, const std::string& dpi, double layer_um,
                         const std::string& mold, double wall_mm, const std::string& split,
                         bool force) {
  fabricate::Request request;
  request.output = output;
  request.format = format;
  request.slices = slices;
  request.mold = mold;
  request.overwrite = force ? Overwrite::replace : Overwrite::refuse;
  fabricate::Options& o = request.options;
  o.scale = scale;
  o.channel_diameter = channel_diameter_mm * 1e-3;
  o.wall = wall_mm * 1e-3;
  o.layer = layer_um * 1e-6;
  const fabricate::Written w = [&] {
    try {
      fabricate::parse_dpi(dpi, o);
      if (!split.empty()) fabricate::parse_split(split, o);
      return fabricate::fabricate_robot(robot, fabricate::provenance_of(robot), request);
    } catch (const fabricate::FabricateError& e) {
      throw fabricate::FabricateError(with_python_argument_names(e.what()));
    } catch (const OutputFileError& e) {
      throw OutputFileError(with_python_argument_names(e.what()));
    }
  }();
  py::dict d;
  d["files"] = w.files;
  d["slices"] = w.slices;
  d["voxels"] = w.fabrication.voxel_count;
  d["chambers"] = w.fabrication.inlets.size();
  py::list groups;
  for (const auto& g : w.fabrication.groups) {
    groups.append(py::dict("name"_a = g.name, "voxels"_a = g.voxels,
                           "triangles"_a = g.mesh.triangles.size(),
                           "volume_mm3"_a = g.mesh.volume() * 1e9));
  }
  d["groups"] = groups;
  d["channel_volume_mm3"] = w.fabrication.channel_volume * 1e9;
  d["split_z_mm"] = w.mold ? py::object(py::float_(w.mold->split_z * 1e3)) : py::none();
  d["summary"] = w.fabrication.summary();
  return d;
}

}  // namespace

void bind_errors(py::module_& m) {
  py::register_exception<RobotFileError>(m, "RobotFileError", PyExc_ValueError).attr("__doc__") =
      "A robot file that is not valid softevo.robot/1 (names file and key).";
  py::register_exception<ConfigError>(m, "ConfigError", PyExc_ValueError).attr("__doc__") =
      "A config that is not valid (names file, line, key and the allowed values).";
  py::register_exception<io::ArchiveError>(m, "ArchiveError", PyExc_OSError).attr("__doc__") =
      "A missing, foreign or malformed run archive (names the file and the object).";
  py::register_exception<OutputFileError>(m, "OutputFileError", PyExc_OSError).attr("__doc__") =
      "An output file that may not be written (symlink, special file, existing file).";
  py::register_exception<fabricate::FabricateError>(m, "FabricateError", PyExc_ValueError)
      .attr("__doc__") =
      "A robot or option that Robot.fabricate refuses (names the option or the chamber).";
}

void bind_robots(py::module_& m) {
  py::class_<RobotFile>(
      m, "Robot", R"(A robot: body (voxel lattice), Elman controller and, when known, the genome
it was developed from (file format softevo.robot/1, docs/model.md §10).

Load one with softevo.load_robot(path); run.genome(id) gives one from a run archive.)")
      .def_static(
          "from_json",
          [](const std::string& text, const std::string& source) {
            return parse_robot_json(text, source);
          },
          "text"_a, "source"_a = "<json>",
          "Parse softevo.robot/1 JSON text; RobotFileError (a ValueError) names `source` and the "
          "key on bad input.")
      .def_static(
          "load", [](const std::filesystem::path& path) { return read_robot_file(path.string()); },
          "path"_a, "Read a robot file (see softevo.load_robot).")
      .def("to_json", &robot_to_json, "The robot as softevo.robot/1 JSON text.")
      .def("_fabricate", &fabricate_robot, "output"_a, "format"_a, "scale"_a, "channel_diameter"_a,
           "slices"_a, "dpi"_a, "layer_um"_a, "mold"_a, "wall"_a, "split"_a, "force"_a)
      .def(
          "save",
          [](const RobotFile& r, const std::filesystem::path& path, bool overwrite) {
            write_robot_file(r, path.string(), overwrite ? Overwrite::replace : Overwrite::refuse);
          },
          "path"_a, "overwrite"_a = true,
          "Write the robot file atomically; OutputFileError (an OSError) for a symlink, a special "
          "file, or an existing file when overwrite is False.")
      .def_property(
          "name", [](const RobotFile& r) { return r.name; },
          [](RobotFile& r, const std::string& name) { r.name = name; }, "The robot's name.")
      .def_property_readonly(
          "lattice",
          [](const RobotFile& r) {
            return py::make_tuple(r.body.lattice[0], r.body.lattice[1], r.body.lattice[2]);
          },
          "Cells along x (forward), y (left), z (up).")
      .def_property_readonly(
          "cells", [](const RobotFile& r) { return cells_array(r.body); },
          "Cell values, shape lattice: 0 empty, 1..10 structural material, "
          "11.. chamber (value - 11). A copy.")
      .def_property_readonly(
          "voxel_size", [](const RobotFile& r) { return r.body.voxel_size; }, "Voxel edge [m].")
      .def_property_readonly(
          "evaluation",
          [](const RobotFile& r) -> py::object {
            if (!r.evaluation) return py::none();
            const RobotEvaluation& e = *r.evaluation;
            py::dict d;
            d["config"] = e.config;
            d["config_hash"] = e.config_hash;
            d["experiment_hash"] = e.experiment_hash;
            d["run"] = e.run;
            d["generation"] = e.generation ? py::object(py::int_(*e.generation)) : py::none();
            d["id"] = e.id ? py::object(py::int_(*e.id)) : py::none();
            d["fitness"] = e.fitness ? py::object(py::float_(*e.fitness)) : py::none();
            d["status"] = e.status;
            return d;
          },
          "The run settings the robot was exported with (a dict: config text, config_hash, "
          "experiment_hash, run, generation, id, archived fitness and status), or None. "
          "evaluate() uses this config when given none.")
      .def_property_readonly(
          "voxels", [](const RobotFile& r) { return voxel_count(r.body); },
          "Number of voxels (structural cells; chamber cells are air).")
      .def_property_readonly(
          "chambers", [](const RobotFile& r) { return r.body.chamber_count(); },
          "Number of pneumatic chambers.")
      .def_property_readonly(
          "closed_loop", [](const RobotFile& r) { return r.controller.closed_loop; },
          "True if the controller reads the chamber pressures (§4.1).")
      .def_property_readonly(
          "directed", [](const RobotFile& r) { return r.controller.directed; },
          "True if the controller reads the direction sensor (§7.3).")
      .def_property_readonly(
          "hidden", [](const RobotFile& r) { return r.controller.hidden; },
          "Hidden (= context) units of the Elman network.")
      .def_property_readonly(
          "frequency", [](const RobotFile& r) { return r.controller.frequency(); },
          "Oscillator frequency [Hz].")
      .def_property_readonly(
          "has_genome", [](const RobotFile& r) { return r.genome.has_value(); },
          "True if the file records the CPPN its body was developed from.")
      .def_property_readonly("controller_parameters", &controller_parameters,
                             "The controller's 9 vectors (docs/model.md §4.4) concatenated in "
                             "canonical order, the last value the oscillator frequency [Hz]. A "
                             "copy (float64).")
      .def("with_controller_parameters", &with_controller_parameters, "values"_a,
           "A copy of the robot whose controller has these parameters (same layout as "
           "controller_parameters). ValueError for a wrong length.")
      .def("__repr__", [](const RobotFile& r) {
        return "<softevo.Robot '" + r.name + "': " + std::to_string(voxel_count(r.body)) +
               " voxels, " + std::to_string(r.body.chamber_count()) + " chambers, " +
               (r.controller.closed_loop ? "closed" : "open") + " loop" +
               (r.controller.directed ? ", directed" : "") + ">";
      });

  py::class_<Config>(m, "Config",
                     R"(A resolved run configuration (configs/*.toml, docs/model.md §1).

Make one with softevo.load_config(path, overrides) or softevo.default_config(task).)")
      .def_property_readonly("text", &canonical_text,
                             "Canonical TOML text: every key in schema order (pressures in bar). "
                             "Parsing it gives back an identical config.")
      .def_property_readonly(
          "hash", [](const Config& c) { return hash_hex(config_hash(c)); },
          "The config identity of run archives: FNV-1a 64 of the text, 16 hex digits.")
      .def_property_readonly(
          "task", [](const Config& c) { return std::string(to_string(c.task.kind)); },
          "task.kind: gait, directed or rotate.")
      .def_property_readonly(
          "control", [](const Config& c) { return std::string(to_string(c.task.control)); },
          "task.control: open or closed.")
      .def_property_readonly(
          "eval_seconds", [](const Config& c) { return c.task.eval_seconds; },
          "task.eval_seconds [s].")
      .def_property_readonly(
          "control_rate", [](const Config& c) { return c.task.control_rate; },
          "task.control_rate [Hz].")
      .def_property_readonly(
          "seed", [](const Config& c) { return c.run.seed; }, "run.seed.")
      .def_property_readonly(
          "experiment", [](const Config& c) { return experiment_name(c); },
          "Experiment name, e.g. gait-open.")
      .def("__eq__",
           [](const Config& a, const Config& b) { return canonical_text(a) == canonical_text(b); })
      .def("__repr__", [](const Config& c) {
        return "<softevo.Config " + experiment_name(c.task) + " " + hash_hex(config_hash(c)) + ">";
      });

  // Python's overrides are named as Python passes them: overrides["neat.pop_size"] = 4.
  m.def(
      "_load_config",
      [](const std::string& path, const std::vector<std::string>& overrides) {
        return load_config(path, overrides, OverrideOrigin::python);
      },
      "path"_a, "overrides"_a);
  m.def(
      "_parse_config",
      [](const std::string& text, const std::string& source,
         const std::vector<std::string>& overrides) {
        return parse_config(text, source, overrides, OverrideOrigin::python);
      },
      "text"_a, "source"_a, "overrides"_a);
  m.def("_develop_robot", &develop_robot, "robot"_a, "config"_a);
  m.def("_develop_genome", &develop_genome, "genome"_a, "config"_a);
  m.def(
      "status_name",
      [](int code) {
        if (code < 0 || code > static_cast<int>(EvalStatus::invalid_body))
          throw py::value_error("status code " + std::to_string(code) + " is not an EvalStatus");
        return std::string(to_string(static_cast<EvalStatus>(code)));
      },
      "code"_a, "The name of an archived status code (0 = ok, 1 = killed: flipped, ...).");
}

}  // namespace softevo::python
