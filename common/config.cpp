// Strict TOML config: the schema below is the single list of every key, its type, its allowed
// values and its unit conversion. Parsing, validation, printing and hashing all walk it, so a key
// cannot be parsed but not printed (or hashed).
#include "common/config.hpp"
#include "common/closest_word.hpp"
#include "common/config_identity.hpp"
#include "common/fnv1a.hpp"
#include "common/input_file.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <sstream>
#include <string_view>
#include <variant>

#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

namespace softevo {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPascalPerBar = 1.0e5;

using Target =
    std::variant<double*, std::int64_t*, bool*, std::string*, TaskKind*, std::vector<double>*,
                 std::vector<std::int64_t>*, std::vector<std::string>*, FailurePolicy*,
                 ControlLoop*, Integrator*, GroundKind*, HeightfieldKind*, TerrainResample*,
                 SupplyScaling*, CrossoverMethod*, ControllerInit*, DistanceInput*, LearningMethod*,
                 Inheritance*>;

struct KeyDef {
  const char* section;
  const char* key;
  Target target;
  double min = -kInf;  // inclusive range of numbers (each element of a number list)
  double max = kInf;
  // allowed strings (each element of a string list); a choice enum or TaskKind: its names
  std::vector<std::string> allowed = {};
  double scale = 1.0;           // config unit -> SI (bar -> Pa)
  const char* unit = "";        // config unit, for messages
  std::size_t list_length = 0;  // exact list length, 0 = any non-empty length
  bool min_exclusive = false;
  // A key of one task only: printed (and hashed) only when task.kind is that task, and an error
  // to set for another task. Keys of the tasks that predate this (task.directions and
  // task.path_penalty_weight of the directed task) stay in every canonical text, because the
  // config hash of every existing archive covers them.
  std::optional<TaskKind> only_for_task = std::nullopt;
  // A key printed (and hashed) only when this holds (keys added after archives existed: at
  // their default they leave the canonical text, and so every existing config hash, unchanged).
  bool (*printed_if)(const Config&) = nullptr;
  // A key that is an error to set unless this holds (it would be ignored), and why.
  bool (*settable_if)(const Config&) = nullptr;
  const char* settable_text = "";
};

// `def` printed and settable only when `when` holds (`why` says when, for the error).
KeyDef only_when(KeyDef def, bool (*when)(const Config&), const char* why) {
  def.printed_if = when;
  def.settable_if = when;
  def.settable_text = why;
  return def;
}
bool failed_generations_not_default(const Config& c) {
  return c.run.stop_after_failed_generations != RunConfig{}.stop_after_failed_generations;
}
bool terrain_not_flat(const Config& c) {
  return c.terrain.kind != GroundKind::flat;
}
bool terrain_heightfield(const Config& c) {
  return c.terrain.kind == GroundKind::heightfield;
}
bool terrain_bumps(const Config& c) {
  return terrain_heightfield(c) && c.terrain.heightfield == HeightfieldKind::bumps;
}
bool terrain_steps(const Config& c) {
  return terrain_heightfield(c) && c.terrain.heightfield == HeightfieldKind::steps;
}
bool terrain_slope(const Config& c) {
  return terrain_heightfield(c) && c.terrain.heightfield == HeightfieldKind::slope;
}
// When a key of heightfield `kind` applies, and the condition's text for the error.
struct HeightfieldCondition {
  bool (*holds)(const Config&);
  const char* text;
};
HeightfieldCondition on_heightfield(HeightfieldKind kind) {
  switch (kind) {
    case HeightfieldKind::bumps:
      return {terrain_bumps, "terrain.kind = \"heightfield\" and terrain.heightfield = \"bumps\""};
    case HeightfieldKind::steps:
      return {terrain_steps, "terrain.kind = \"heightfield\" and terrain.heightfield = \"steps\""};
    case HeightfieldKind::slope:
      break;
  }
  return {terrain_slope, "terrain.kind = \"heightfield\" and terrain.heightfield = \"slope\""};
}
// The keys of the heightfield's numbers (common/terrain_shape.hpp), in its table's order: each
// printed and settable only on its heightfield.
std::vector<KeyDef> terrain_shape_rows(TerrainShape& shape) {
  std::vector<KeyDef> rows;
  for (const TerrainShapeField& f : kTerrainShapeFields) {
    const HeightfieldCondition when = on_heightfield(f.heightfield);
    rows.push_back(only_when({.section = "terrain",
                              .key = f.key,
                              .target = &(shape.*f.member),
                              .min = f.min,
                              .max = f.max,
                              .unit = f.unit,
                              .min_exclusive = f.min_exclusive},
                             when.holds, when.text));
  }
  return rows;
}
bool learning_on(const Config& c) {
  return c.learning.method != LearningMethod::none;
}
bool supply_scaled(const Config& c) {
  return c.pneumatics.supply_pressure_scaling != SupplyScaling::none;
}
bool oscillator_inputs_removed(const Config& c) {
  return !c.controller.oscillator_inputs;
}
bool controller_init_not_random(const Config& c) {
  return c.controller.init != ControllerInit::random;
}

std::vector<std::string> task_kind_names() {
  std::vector<std::string> names;
  for (TaskKind k : task_kinds()) names.emplace_back(to_string(k));
  return names;
}

// The strings a string, choice or string-list key accepts (empty: any string).
std::vector<std::string> allowed_strings(const KeyDef& def) {
  return std::visit(
      [&](auto* target) -> std::vector<std::string> {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (ConfigChoice<T>) {
          return choice_names<T>();
        } else if constexpr (std::is_same_v<T, TaskKind>) {
          return task_kind_names();
        } else {
          return def.allowed;
        }
      },
      def.target);
}

const std::vector<std::string> kSections = {
    "run", "task", "physics", "terrain", "pneumatics", "controller", "body", "neat", "learning"};

std::vector<KeyDef> schema(Config& c) {
  const std::vector<std::string> activations = {"sigmoid", "sin",     "abs",   "square",
                                                "exp",     "clamped", "gauss", "tanh"};
  auto& r = c.run;
  auto& t = c.task;
  auto& p = c.physics;
  auto& tr = c.terrain;
  auto& pn = c.pneumatics;
  auto& ct = c.controller;
  auto& b = c.body;
  auto& l = c.learning;
  auto& n = c.neat;
  std::vector<KeyDef> rows = {
      {.section = "run", .key = "seed", .target = &r.seed, .min = 0, .max = 9.0e15},
      {.section = "run", .key = "generations", .target = &r.generations, .min = 0, .max = 1.0e7},
      {.section = "run",
       .key = "eval_timeout_seconds",
       .target = &r.eval_timeout_seconds,
       .min = 0,
       .unit = "s"},
      {.section = "run", .key = "on_failure", .target = &r.on_failure},
      {.section = "run",
       .key = "stop_after_failed_generations",
       .target = &r.stop_after_failed_generations,
       .min = 0,
       .max = 1.0e7,
       .printed_if = failed_generations_not_default},

      {.section = "task", .key = "kind", .target = &t.kind},
      {.section = "task", .key = "control", .target = &t.control},
      {.section = "task",
       .key = "eval_seconds",
       .target = &t.eval_seconds,
       .min = 0,
       .max = 3600,
       .unit = "s",
       .min_exclusive = true},
      {.section = "task",
       .key = "control_rate",
       .target = &t.control_rate,
       .min = 0,
       .max = 10000,
       .unit = "Hz",
       .min_exclusive = true},
      {.section = "task",
       .key = "directions",
       .target = &t.directions,
       .min = -180,
       .max = 180,
       .unit = "deg"},
      {.section = "task", .key = "path_penalty_weight", .target = &t.path_penalty_weight, .min = 0},
      {.section = "task",
       .key = "rotate_travel_penalty",
       .target = &t.rotate_travel_penalty,
       .min = 0,
       .unit = "rad per body length",
       .only_for_task = TaskKind::rotate},

      {.section = "physics", .key = "integrator", .target = &p.integrator},
      {.section = "physics",
       .key = "dt_fraction",
       .target = &p.dt_fraction,
       .min = 0,
       .max = 1.0,
       .min_exclusive = true},
      {.section = "physics",
       .key = "voxel_size",
       .target = &p.voxel_size,
       .min = 0,
       .max = 10,
       .unit = "m",
       .min_exclusive = true},
      {.section = "physics",
       .key = "gravity",
       .target = &p.gravity,
       .min = 0,
       .max = 1000,
       .unit = "m/s^2"},
      {.section = "physics", .key = "floor", .target = &p.floor},
      {.section = "physics", .key = "self_collision", .target = &p.self_collision},
      {.section = "physics",
       .key = "static_friction",
       .target = &p.static_friction,
       .min = 0,
       .max = 100},
      {.section = "physics",
       .key = "kinetic_friction",
       .target = &p.kinetic_friction,
       .min = 0,
       .max = 100},
      {.section = "physics",
       .key = "internal_damping",
       .target = &p.internal_damping,
       .min = 0,
       .max = 10},
      {.section = "physics",
       .key = "global_damping",
       .target = &p.global_damping,
       .min = 0,
       .max = 10},
      {.section = "physics",
       .key = "collision_damping",
       .target = &p.collision_damping,
       .min = 0,
       .max = 10},
      {.section = "physics",
       .key = "youngs_modulus_min",
       .target = &p.youngs_modulus_min,
       .min = 0,
       .max = 1e12,
       .unit = "Pa",
       .min_exclusive = true},
      {.section = "physics",
       .key = "youngs_modulus_max",
       .target = &p.youngs_modulus_max,
       .min = 0,
       .max = 1e12,
       .unit = "Pa",
       .min_exclusive = true},
      {.section = "physics",
       .key = "material_count",
       .target = &p.material_count,
       .min = 1,
       .max = 10},
      {.section = "physics",
       .key = "density",
       .target = &p.density,
       .min = 0,
       .max = 1e6,
       .unit = "kg/m^3",
       .min_exclusive = true},

      {.section = "terrain", .key = "kind", .target = &tr.kind, .printed_if = terrain_not_flat},
      only_when({.section = "terrain", .key = "heightfield", .target = &tr.heightfield},
                terrain_heightfield, "terrain.kind = \"heightfield\""),
      only_when({.section = "terrain", .key = "seed", .target = &tr.seed, .min = 0, .max = 9.0e15},
                terrain_not_flat, "terrain.kind is not \"flat\""),
      only_when({.section = "terrain", .key = "resample", .target = &tr.resample}, terrain_not_flat,
                "terrain.kind is not \"flat\""),

      {.section = "pneumatics",
       .key = "supply_pressure",
       .target = &pn.supply_pressure,
       .min = 0,
       .max = 100,
       .scale = kPascalPerBar,
       .unit = "bar"},
      {.section = "pneumatics",
       .key = "ambient_pressure",
       .target = &pn.ambient_pressure,
       .min = 0,
       .max = 100,
       .scale = kPascalPerBar,
       .unit = "bar"},
      {.section = "pneumatics",
       .key = "conductivity",
       .target = &pn.conductivity,
       .min = 0,
       .max = 1000,
       .unit = "m^3/(bar s)"},
      {.section = "pneumatics",
       .key = "valve_cutoff",
       .target = &pn.valve_cutoff,
       .min = 0,
       .max = 1e4,
       .unit = "Hz",
       .min_exclusive = true},
      {.section = "pneumatics",
       .key = "valve_filter_stages",
       .target = &pn.valve_filter_stages,
       .min = 0,
       .max = 16},
      {.section = "pneumatics",
       .key = "valve_filter_q",
       .target = &pn.valve_filter_q,
       .min = 0,
       .max = 100,
       .min_exclusive = true},
      {.section = "pneumatics",
       .key = "initial_sensor_pressure",
       .target = &pn.initial_sensor_pressure,
       .min = 0,
       .max = 100,
       .scale = kPascalPerBar,
       .unit = "bar"},
      {.section = "pneumatics",
       .key = "supply_pressure_scaling",
       .target = &pn.supply_pressure_scaling,
       .printed_if = supply_scaled},
      only_when({.section = "pneumatics",
                 .key = "scaling_reference_volume",
                 .target = &pn.scaling_reference_volume,
                 .min = 0,
                 .max = 1,
                 .unit = "m^3",
                 .min_exclusive = true},
                supply_scaled, "pneumatics.supply_pressure_scaling = \"inverse_volume\""),
      only_when({.section = "pneumatics",
                 .key = "max_supply_pressure",
                 .target = &pn.max_supply_pressure,
                 .min = 0,
                 .max = 100,
                 .scale = kPascalPerBar,
                 .unit = "bar",
                 .min_exclusive = true},
                supply_scaled, "pneumatics.supply_pressure_scaling = \"inverse_volume\""),

      {.section = "controller", .key = "hidden", .target = &ct.hidden, .min = 1, .max = 64},
      {.section = "controller", .key = "crossover_method", .target = &ct.crossover_method},
      {.section = "controller",
       .key = "weight_init_sd",
       .target = &ct.weight_init_sd,
       .min = 0,
       .max = 100},
      {.section = "controller",
       .key = "gene_limit",
       .target = &ct.gene_limit,
       .min = 0,
       .max = 1000,
       .min_exclusive = true},
      {.section = "controller",
       .key = "freq_min",
       .target = &ct.freq_min,
       .min = 0,
       .max = 1000,
       .unit = "Hz",
       .min_exclusive = true},
      {.section = "controller",
       .key = "freq_max",
       .target = &ct.freq_max,
       .min = 0,
       .max = 1000,
       .unit = "Hz",
       .min_exclusive = true},
      {.section = "controller",
       .key = "freq_step_size_init",
       .target = &ct.freq_step_size_init,
       .min = 0,
       .max = 1000,
       .unit = "Hz"},
      {.section = "controller",
       .key = "oscillator_inputs",
       .target = &ct.oscillator_inputs,
       .printed_if = oscillator_inputs_removed},
      {.section = "controller",
       .key = "init",
       .target = &ct.init,
       .printed_if = controller_init_not_random},
      only_when({.section = "controller",
                 .key = "init_perturbation_sd",
                 .target = &ct.init_perturbation_sd,
                 .min = 0,
                 .max = 5},
                controller_init_not_random, "controller.init = \"oscillator\""),

      {.section = "body",
       .key = "lattice",
       .target = &b.lattice,
       .min = 2,
       .max = 64,
       .unit = "cells",
       .list_length = 3},
      {.section = "body", .key = "distance_input", .target = &b.distance_input},
      {.section = "body", .key = "presence_threshold", .target = &b.presence_threshold},
      {.section = "body", .key = "pneumatic_threshold", .target = &b.pneumatic_threshold},
      {.section = "body", .key = "max_chambers", .target = &b.max_chambers, .min = 1, .max = 10},

      {.section = "neat", .key = "pop_size", .target = &n.pop_size, .min = 2, .max = 1e6},
      {.section = "neat",
       .key = "compatibility_threshold",
       .target = &n.compatibility_threshold,
       .min = 0,
       .min_exclusive = true},
      {.section = "neat",
       .key = "compatibility_disjoint_coefficient",
       .target = &n.compatibility_disjoint_coefficient,
       .min = 0},
      {.section = "neat",
       .key = "compatibility_weight_coefficient",
       .target = &n.compatibility_weight_coefficient,
       .min = 0},
      {.section = "neat", .key = "conn_add_prob", .target = &n.conn_add_prob, .min = 0, .max = 1},
      {.section = "neat",
       .key = "conn_delete_prob",
       .target = &n.conn_delete_prob,
       .min = 0,
       .max = 1},
      {.section = "neat", .key = "node_add_prob", .target = &n.node_add_prob, .min = 0, .max = 1},
      {.section = "neat",
       .key = "node_delete_prob",
       .target = &n.node_delete_prob,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "activation_default",
       .target = &n.activation_default,
       .allowed = {"random", "sigmoid", "sin", "abs", "square", "exp", "clamped", "gauss", "tanh"}},
      {.section = "neat",
       .key = "activation_mutate_rate",
       .target = &n.activation_mutate_rate,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "activation_options",
       .target = &n.activation_options,
       .allowed = activations},
      {.section = "neat", .key = "bias_init_mean", .target = &n.bias_init_mean},
      {.section = "neat", .key = "bias_init_stdev", .target = &n.bias_init_stdev, .min = 0},
      {.section = "neat", .key = "bias_max_value", .target = &n.bias_max_value},
      {.section = "neat", .key = "bias_min_value", .target = &n.bias_min_value},
      {.section = "neat", .key = "bias_mutate_power", .target = &n.bias_mutate_power, .min = 0},
      {.section = "neat",
       .key = "bias_mutate_rate",
       .target = &n.bias_mutate_rate,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "bias_replace_rate",
       .target = &n.bias_replace_rate,
       .min = 0,
       .max = 1},
      {.section = "neat", .key = "weight_init_mean", .target = &n.weight_init_mean},
      {.section = "neat", .key = "weight_init_stdev", .target = &n.weight_init_stdev, .min = 0},
      {.section = "neat", .key = "weight_max_value", .target = &n.weight_max_value},
      {.section = "neat", .key = "weight_min_value", .target = &n.weight_min_value},
      {.section = "neat", .key = "weight_mutate_power", .target = &n.weight_mutate_power, .min = 0},
      {.section = "neat",
       .key = "weight_mutate_rate",
       .target = &n.weight_mutate_rate,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "weight_replace_rate",
       .target = &n.weight_replace_rate,
       .min = 0,
       .max = 1},
      {.section = "neat", .key = "response_init_mean", .target = &n.response_init_mean},
      {.section = "neat", .key = "response_init_stdev", .target = &n.response_init_stdev, .min = 0},
      {.section = "neat", .key = "response_max_value", .target = &n.response_max_value},
      {.section = "neat", .key = "response_min_value", .target = &n.response_min_value},
      {.section = "neat",
       .key = "response_mutate_power",
       .target = &n.response_mutate_power,
       .min = 0},
      {.section = "neat",
       .key = "response_mutate_rate",
       .target = &n.response_mutate_rate,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "response_replace_rate",
       .target = &n.response_replace_rate,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "enabled_mutate_rate",
       .target = &n.enabled_mutate_rate,
       .min = 0,
       .max = 1},
      {.section = "neat",
       .key = "max_stagnation",
       .target = &n.max_stagnation,
       .min = 1,
       .max = 1e9},
      {.section = "neat",
       .key = "species_elitism",
       .target = &n.species_elitism,
       .min = 0,
       .max = 1e9},
      {.section = "neat", .key = "elitism", .target = &n.elitism, .min = 0, .max = 1e9},
      {.section = "neat",
       .key = "survival_threshold",
       .target = &n.survival_threshold,
       .min = 0,
       .max = 1,
       .min_exclusive = true},
      {.section = "neat",
       .key = "tournament_size",
       .target = &n.tournament_size,
       .min = 1,
       .max = 1e9},
      {.section = "neat",
       .key = "min_species_size",
       .target = &n.min_species_size,
       .min = 1,
       .max = 1e9},

      {.section = "learning", .key = "method", .target = &l.method, .printed_if = learning_on},
      only_when({.section = "learning",
                 .key = "evaluations",
                 .target = &l.evaluations,
                 .min = 2,
                 .max = 1e9},
                learning_on, "learning.method is not \"none\""),
      only_when({.section = "learning",
                 .key = "population",
                 .target = &l.population,
                 .min = 1,
                 .max = 1e9},
                learning_on, "learning.method is not \"none\""),
      only_when({.section = "learning", .key = "inheritance", .target = &l.inheritance},
                learning_on, "learning.method is not \"none\""),
      only_when({.section = "learning",
                 .key = "step_size_factor",
                 .target = &l.step_size_factor,
                 .min = 0,
                 .max = 1e6,
                 .min_exclusive = true},
                learning_on, "learning.method is not \"none\""),
      only_when({.section = "learning",
                 .key = "body_mutate_power_factor",
                 .target = &l.body_mutate_power_factor,
                 .min = 0,
                 .max = 1e6},
                learning_on, "learning.method is not \"none\""),
  };
  // The heightfield's numbers follow terrain.heightfield: their place in the canonical text.
  const auto heightfield = std::find_if(rows.begin(), rows.end(), [](const KeyDef& def) {
    return std::string_view(def.section) == "terrain" && std::string_view(def.key) == "heightfield";
  });
  const std::vector<KeyDef> shape = terrain_shape_rows(tr.shape);
  rows.insert(heightfield + 1, shape.begin(), shape.end());
  return rows;
}

// Shortest text that parses back to exactly `v` (std::to_chars round-trip guarantee), written
// so that TOML reads it as a float.
std::string format_double(double v) {
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

std::string join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? sep : "") + items[i];
  return out;
}

std::string range_text(const KeyDef& def, bool integer) {
  const char* kind = integer ? "integer" : "number";
  const bool has_min = def.min != -kInf;
  const bool has_max = def.max != kInf;
  auto num = [&](double v) {
    return integer ? std::to_string(static_cast<long long>(v)) : format_double(v);
  };
  std::string unit = *def.unit ? std::string(" ") + def.unit : "";
  if (has_min && has_max) {
    return std::string(kind) + (def.min_exclusive ? " in (" : " in [") + num(def.min) + ", " +
           num(def.max) + "]" + unit;
  }
  if (has_min)
    return std::string(kind) + (def.min_exclusive ? " > " : " >= ") + num(def.min) + unit;
  if (has_max) return std::string(kind) + " <= " + num(def.max) + unit;
  return std::string(kind) + unit;
}

std::string allowed_text(const KeyDef& def) {
  return std::visit(
      [&](auto* target) -> std::string {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, double>) return range_text(def, false);
        if constexpr (std::is_same_v<T, std::int64_t>) return range_text(def, true);
        if constexpr (std::is_same_v<T, bool>) return "true or false";
        if constexpr (std::is_same_v<T, std::string> || std::is_same_v<T, TaskKind> ||
                      ConfigChoice<T>) {
          std::vector<std::string> q;
          for (const auto& a : allowed_strings(def)) q.push_back(quote(a));
          return "one of " + join(q);
        }
        if constexpr (std::is_same_v<T, std::vector<double>>) {
          return std::string(def.list_length ? "array of " + std::to_string(def.list_length)
                                             : "non-empty array of") +
                 " numbers, each " + range_text(def, false);
        }
        if constexpr (std::is_same_v<T, std::vector<std::int64_t>>) {
          return std::string(def.list_length ? "array of " + std::to_string(def.list_length)
                                             : "non-empty array of") +
                 " integers, each " + range_text(def, true);
        }
        if constexpr (std::is_same_v<T, std::vector<std::string>>) {
          std::vector<std::string> q;
          for (const auto& a : def.allowed) q.push_back(quote(a));
          return "non-empty array of distinct strings from " + join(q);
        }
        return "";
      },
      def.target);
}

std::string suggestion(const std::string& name, const std::vector<std::string>& candidates) {
  const std::string best = closest_word(name, candidates);
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

struct Location {
  std::string source;  // file name or "--set ..."
  std::int64_t line = 0;
  std::string prefix() const {
    return line > 0 ? source + ":" + std::to_string(line) + ": " : source + ": ";
  }
};

[[noreturn]] void fail(const Location& at, const std::string& message) {
  throw ConfigError(at.prefix() + message);
}

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    default:
      return "a date/time";
  }
}

double number_of(const toml::node& node, const KeyDef& def, const Location& at,
                 const std::string& name, bool integer) {
  double v = 0;
  if (integer) {
    if (!node.is_integer()) {
      fail(at, name + " must be " + allowed_text(def) + ", got " + type_name(node));
    }
    v = static_cast<double>(node.as_integer()->get());
  } else {
    if (node.is_integer()) {
      v = static_cast<double>(node.as_integer()->get());
    } else if (node.is_floating_point()) {
      v = node.as_floating_point()->get();
    } else {
      fail(at, name + " must be " + allowed_text(def) + ", got " + type_name(node));
    }
  }
  const bool below = def.min_exclusive ? !(v > def.min) : !(v >= def.min);
  if (!std::isfinite(v) || below || !(v <= def.max)) {
    std::string shown;
    if (integer) {
      shown = std::to_string(node.as_integer()->get());
    } else {
      shown = format_double(v);
    }
    fail(at, name + " = " + shown + " is out of range; allowed: " + allowed_text(def));
  }
  return v;
}

std::string string_of(const toml::node& node, const KeyDef& def, const Location& at,
                      const std::string& name) {
  if (!node.is_string()) {
    fail(at, name + " must be " + allowed_text(def) + ", got " + type_name(node));
  }
  std::string v = node.as_string()->get();
  const std::vector<std::string> allowed = allowed_strings(def);
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
    fail(at, name + " = " + quote(v) + " is not allowed" + suggestion(v, allowed) +
                 "; allowed: " + allowed_text(def));
  }
  return v;
}

// True for text that is a number too large (or too small) for a double or an int64, such as
// 1e999 or 99999999999999999999: TOML refuses it as a syntax error, which hides the real cause.
bool is_unrepresentable_number(const std::string& text) {
  if (text.empty()) return false;
  std::string digits;
  for (std::size_t i = text[0] == '+' || text[0] == '-' ? 1 : 0; i < text.size(); ++i)
    if (text[i] != '_') digits += text[i];
  if (!digits.empty() && digits.find_first_not_of("0123456789") == std::string::npos) {
    std::int64_t v = 0;
    return std::from_chars(digits.data(), digits.data() + digits.size(), v).ec ==
           std::errc::result_out_of_range;
  }
  errno = 0;
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  return errno == ERANGE && end == text.c_str() + text.size();
}

[[noreturn]] void fail_unrepresentable(const KeyDef& def, const Location& at,
                                       const std::string& text) {
  fail(at, std::string(def.section) + "." + def.key + " = " + text +
               " is out of range (not representable as a 64-bit number); allowed: " +
               allowed_text(def));
}

void assign(const KeyDef& def, const toml::node& node, const Location& at) {
  const std::string name = std::string(def.section) + "." + def.key;
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, double>) {
          *target = number_of(node, def, at, name, false) * def.scale;
        } else if constexpr (std::is_same_v<T, std::int64_t>) {
          number_of(node, def, at, name, true);  // validates type and range
          *target = node.as_integer()->get();
        } else if constexpr (std::is_same_v<T, bool>) {
          if (!node.is_boolean()) {
            fail(at, name + " must be true or false, got " + type_name(node));
          }
          *target = node.as_boolean()->get();
        } else if constexpr (std::is_same_v<T, std::string>) {
          *target = string_of(node, def, at, name);
        } else if constexpr (std::is_same_v<T, TaskKind>) {
          *target = *task_kind_from_string(string_of(node, def, at, name));  // allowed: checked
        } else if constexpr (ConfigChoice<T>) {
          *target = *choice_from_string<T>(string_of(node, def, at, name));  // allowed: checked
        } else {
          if (!node.is_array()) {
            fail(at, name + " must be " + allowed_text(def) + ", got " + type_name(node));
          }
          const toml::array& arr = *node.as_array();
          if (arr.empty() || (def.list_length && arr.size() != def.list_length)) {
            fail(at, name + " has " + std::to_string(arr.size()) +
                         " elements; allowed: " + allowed_text(def));
          }
          T values;
          for (std::size_t i = 0; i < arr.size(); ++i) {
            const std::string element = name + "[" + std::to_string(i) + "]";
            if constexpr (std::is_same_v<T, std::vector<double>>) {
              values.push_back(number_of(arr[i], def, at, element, false) * def.scale);
            } else if constexpr (std::is_same_v<T, std::vector<std::int64_t>>) {
              values.push_back(
                  static_cast<std::int64_t>(number_of(arr[i], def, at, element, true)));
            } else {
              std::string v = string_of(arr[i], def, at, element);
              if (std::find(values.begin(), values.end(), v) != values.end()) {
                fail(at, element + " = " + quote(v) + " is listed twice");
              }
              values.push_back(std::move(v));
            }
          }
          *target = std::move(values);
        }
      },
      def.target);
}

std::vector<std::string> keys_of(const std::vector<KeyDef>& defs, const std::string& section) {
  std::vector<std::string> keys;
  for (const auto& d : defs) {
    if (section == d.section) keys.emplace_back(d.key);
  }
  return keys;
}

const KeyDef* find_def(const std::vector<KeyDef>& defs, const std::string& section,
                       const std::string& key) {
  for (const auto& d : defs) {
    if (section == d.section && key == d.key) return &d;
  }
  return nullptr;
}

void check_known_section(const std::string& section, const Location& at) {
  if (std::find(kSections.begin(), kSections.end(), section) == kSections.end()) {
    fail(at, "unknown section [" + section + "]" + suggestion(section, kSections) +
                 "; allowed sections: " + join(kSections));
  }
}

const KeyDef& known_key(const std::vector<KeyDef>& defs, const std::string& section,
                        const std::string& key, const Location& at) {
  const KeyDef* def = find_def(defs, section, key);
  if (!def) {
    const auto keys = keys_of(defs, section);
    fail(at, "unknown key '" + section + "." + key + "'" + suggestion(key, keys) +
                 "; allowed keys in [" + section + "]: " + join(keys));
  }
  return *def;
}

// Relations between keys that no single range can express.
void check_consistency(const Config& c, const std::string& source) {
  const Location at{source, 0};
  if (c.physics.youngs_modulus_min > c.physics.youngs_modulus_max) {
    fail(at, "physics.youngs_modulus_min must be <= physics.youngs_modulus_max");
  }
  // Ground that cannot work: a tread shorter than a voxel puts a riser under every voxel centre
  // (physics/terrain.cpp refuses it, so every evaluation would fail), and value noise of cells
  // below a voxel is sampled less than once per cell (far below, it reads as flat ground).
  if (terrain_steps(c) && !(c.terrain.shape.step_spacing >= c.physics.voxel_size)) {
    fail(at, "terrain.step_spacing = " + format_double(c.terrain.shape.step_spacing) +
                 " m must be at least one voxel (physics.voxel_size = " +
                 format_double(c.physics.voxel_size) + " m)");
  }
  if (terrain_bumps(c) && !(c.terrain.shape.correlation_length >= c.physics.voxel_size)) {
    fail(at, "terrain.correlation_length = " + format_double(c.terrain.shape.correlation_length) +
                 " m must be at least one voxel (physics.voxel_size = " +
                 format_double(c.physics.voxel_size) +
                 " m): finer noise is not resolved by the voxel contacts");
  }
  if (c.controller.freq_min > c.controller.freq_max) {
    fail(at, "controller.freq_min must be <= controller.freq_max");
  }
  if (supply_scaled(c) && c.pneumatics.max_supply_pressure < c.pneumatics.supply_pressure) {
    fail(at, "pneumatics.max_supply_pressure = " +
                 format_double(c.pneumatics.max_supply_pressure / kPascalPerBar) +
                 " bar must be >= pneumatics.supply_pressure = " +
                 format_double(c.pneumatics.supply_pressure / kPascalPerBar) +
                 " bar (the reference chamber keeps supply_pressure)");
  }
  // Below ambient the scaled gauge would be negative and grow without bound for small chambers.
  if (supply_scaled(c) && !(c.pneumatics.supply_pressure > c.pneumatics.ambient_pressure)) {
    fail(at, "pneumatics.supply_pressure_scaling = " +
                 quote(to_string(c.pneumatics.supply_pressure_scaling)) +
                 " needs pneumatics.supply_pressure > pneumatics.ambient_pressure (it scales the "
                 "gauge pressure above ambient)");
  }
  // Without pressure sensors the hand-made oscillator has nothing to switch on, and an open-loop
  // controller without oscillator inputs has no input that changes.
  if (c.controller.init == ControllerInit::oscillator && c.task.control != ControlLoop::closed) {
    fail(at,
         "controller.init = \"oscillator\" needs task.control = \"closed\" (it switches on "
         "the pressure sensors), got task.control = " +
             quote(to_string(c.task.control)));
  }
  if (!c.controller.oscillator_inputs && c.task.control != ControlLoop::closed) {
    fail(at,
         "controller.oscillator_inputs = false needs task.control = \"closed\" (an open-loop "
         "controller without oscillator inputs gets no input that changes), got "
         "task.control = " +
             quote(to_string(c.task.control)));
  }
  if (learning_on(c) && c.learning.evaluations < 1 + c.learning.population) {
    fail(at,
         "learning.evaluations = " + std::to_string(c.learning.evaluations) +
             " must be >= 1 + learning.population = " + std::to_string(1 + c.learning.population) +
             " (the inherited controller's evaluation and one iteration of candidates)");
  }
  if (learning_on(c) && (c.learning.evaluations - 1) / c.learning.population > 100000) {
    fail(at, "learning.evaluations = " + std::to_string(c.learning.evaluations) +
                 " gives more than 100000 iterations of learning.population = " +
                 std::to_string(c.learning.population) + " candidates (the archive's limit)");
  }
  // A candidate is evaluated under its own work-unit id: on a ground drawn per evaluation it
  // would compete on another ground than its body's, and the learned robot would not replay.
  if (learning_on(c) && terrain_not_flat(c) &&
      c.terrain.resample == TerrainResample::per_evaluation) {
    fail(at, "learning.method = " + quote(to_string(c.learning.method)) +
                 " needs terrain.resample = \"per_run\" or \"per_generation\" (candidates of one "
                 "body must be scored on the same ground), got \"per_evaluation\"");
  }
  if (c.neat.bias_min_value > c.neat.bias_max_value) {
    fail(at, "neat.bias_min_value must be <= neat.bias_max_value");
  }
  if (c.neat.weight_min_value > c.neat.weight_max_value) {
    fail(at, "neat.weight_min_value must be <= neat.weight_max_value");
  }
  if (c.neat.response_min_value > c.neat.response_max_value) {
    fail(at, "neat.response_min_value must be <= neat.response_max_value");
  }
  if (c.neat.elitism > c.neat.pop_size) {
    fail(at, "neat.elitism = " + std::to_string(c.neat.elitism) +
                 " must be <= neat.pop_size = " + std::to_string(c.neat.pop_size) +
                 " (the elites of a single species would outnumber the population)");
  }
  if (c.neat.activation_default != "random" &&
      std::find(c.neat.activation_options.begin(), c.neat.activation_options.end(),
                c.neat.activation_default) == c.neat.activation_options.end()) {
    fail(at, "neat.activation_default = " + quote(c.neat.activation_default) +
                 " must be \"random\" or one of neat.activation_options");
  }
}

// Where each key was last set (file line or --set), for checks that follow all overrides.
using SetKeys = std::map<std::string, Location>;

std::string full_name(const KeyDef& def) {
  return std::string(def.section) + "." + def.key;
}

void apply_table(Config& config, const toml::table& root, const std::string& source,
                 SetKeys& set_keys) {
  auto defs = schema(config);
  for (const auto& [section_key, section_node] : root) {
    const std::string section(section_key.str());
    const Location at{source, static_cast<std::int64_t>(section_key.source().begin.line)};
    const toml::table* table = section_node.as_table();
    if (!table) {
      std::string home;
      for (const auto& d : defs) {
        if (section == d.key && home.empty()) home = d.section;  // the first (run.seed)
      }
      fail(at, "key '" + section + "' is outside any section" +
                   (home.empty() ? "" : "; it belongs under [" + home + "]"));
    }
    check_known_section(section, at);
    for (const auto& [key, node] : *table) {
      const Location key_at{source, static_cast<std::int64_t>(key.source().begin.line)};
      const KeyDef& def = known_key(defs, section, std::string(key.str()), key_at);
      assign(def, node, key_at);
      set_keys.insert_or_assign(full_name(def), key_at);
    }
  }
}

void apply_override(Config& config, const std::string& text, SetKeys& set_keys) {
  const Location at{"--set " + text, 0};
  const auto eq = text.find('=');
  const auto dot = text.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
    fail(at, "expected section.key=value");
  }
  const std::string section = text.substr(0, dot);
  const std::string key = text.substr(dot + 1, eq - dot - 1);
  const std::string value = text.substr(eq + 1);
  check_known_section(section, at);
  auto defs = schema(config);
  const KeyDef& def = known_key(defs, section, key, at);
  // The value uses TOML syntax (numbers, true/false, "strings", [arrays]); a bare word that is
  // not valid TOML is taken as a string, so --set physics.integrator=symplectic works.
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    if (is_unrepresentable_number(value)) fail_unrepresentable(def, at, value);
    parsed = toml::table{};
    parsed.insert("v", value);
  }
  assign(def, *parsed.get("v"), at);
  set_keys.insert_or_assign(full_name(def), at);
}

// A key of another task than the configured one would be silently ignored (and left out of the
// hash): say so instead.
void check_task_keys(Config& config, const SetKeys& set_keys) {
  for (const KeyDef& def : schema(config)) {
    if (def.settable_if && !def.settable_if(config)) {
      const auto it = set_keys.find(full_name(def));
      if (it != set_keys.end())
        fail(it->second, full_name(def) + " applies only when " + def.settable_text);
    }
    if (!def.only_for_task || *def.only_for_task == config.task.kind) continue;
    const auto it = set_keys.find(full_name(def));
    if (it != set_keys.end())
      fail(it->second, full_name(def) +
                           " applies to task.kind = " + quote(to_string(*def.only_for_task)) +
                           " only (task.kind is " + quote(to_string(config.task.kind)) + ")");
  }
}

// A TOML syntax error on `at.line` that is a number out of range ("eval_seconds = 1e999" under
// [task]) is reported as such, naming the key; any other syntax error is left to the caller.
void fail_if_unrepresentable_on_line(Config& config, const std::string& toml_text,
                                     const Location& at) {
  static const std::regex header(R"(^\s*\[\s*([A-Za-z0-9_-]+)\s*\]\s*(#.*)?$)");
  static const std::regex assignment(R"(^\s*([A-Za-z0-9_-]+)\s*=\s*([^\s#,\]]+))");
  std::istringstream lines(toml_text);
  std::string text, section;
  for (std::int64_t number = 1; std::getline(lines, text) && number <= at.line; ++number) {
    std::smatch m;
    if (std::regex_search(text, m, header)) section = m[1].str();
    if (number < at.line || !std::regex_search(text, m, assignment)) continue;
    const auto defs = schema(config);
    const KeyDef* def = find_def(defs, section, m[1].str());
    if (def && is_unrepresentable_number(m[2].str())) fail_unrepresentable(*def, at, m[2].str());
  }
}

std::string value_text(const KeyDef& def) {
  return std::visit(
      [&](auto* target) -> std::string {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, double>) return format_double(*target / def.scale);
        if constexpr (std::is_same_v<T, std::int64_t>) return std::to_string(*target);
        if constexpr (std::is_same_v<T, bool>) return *target ? "true" : "false";
        if constexpr (std::is_same_v<T, std::string>) return quote(*target);
        if constexpr (std::is_same_v<T, TaskKind>) return quote(to_string(*target));
        if constexpr (ConfigChoice<T>) return quote(to_string(*target));
        if constexpr (std::is_same_v<T, std::vector<double>>) {
          std::vector<std::string> items;
          for (double v : *target) items.push_back(format_double(v / def.scale));
          return "[" + join(items) + "]";
        }
        if constexpr (std::is_same_v<T, std::vector<std::int64_t>>) {
          std::vector<std::string> items;
          for (auto v : *target) items.push_back(std::to_string(v));
          return "[" + join(items) + "]";
        }
        if constexpr (std::is_same_v<T, std::vector<std::string>>) {
          std::vector<std::string> items;
          for (const auto& v : *target) items.push_back(quote(v));
          return "[" + join(items) + "]";
        }
        return "";
      },
      def.target);
}

}  // namespace

Config parse_config(const std::string& toml_text, const std::string& source_name,
                    const std::vector<std::string>& overrides) {
  Config config;
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    const auto line = static_cast<std::int64_t>(e.source().begin.line);
    fail_if_unrepresentable_on_line(config, toml_text, {source_name, line});
    throw ConfigError(source_name + ":" + std::to_string(line) +
                      ": TOML syntax error: " + std::string(e.description()));
  }
  SetKeys set_keys;
  apply_table(config, root, source_name, set_keys);
  for (const auto& o : overrides) apply_override(config, o, set_keys);
  check_task_keys(config, set_keys);
  check_consistency(config, source_name);
  return config;
}

Config load_config(const std::string& path, const std::vector<std::string>& overrides) {
  // A directory opens as a stream that reads as empty on Linux: it would silently be a config
  // of all defaults, that is a full-size run.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError(path + ": is a directory, not a config file");
  std::string text;
  try {
    text = read_input_file(path, InputLimits::config_bytes, "config file");
  } catch (const InputFileError& e) {
    throw ConfigError(e.what());
  }
  return parse_config(text, path, overrides);
}

Config apply_overrides(const Config& base, const std::vector<std::string>& overrides) {
  // The canonical text parses back to an identical Config, so only the overrides change.
  return parse_config(canonical_text(base), "<resolved config>", overrides);
}

std::string toml_number(double v) {
  return format_double(v);
}

std::string canonical_text(const Config& config) {
  Config copy = config;  // schema() binds to a mutable Config; printing never changes it
  const auto defs = schema(copy);
  std::string out;
  for (const auto& section : kSections) {
    std::string keys;
    for (const auto& d : defs) {
      if (d.only_for_task && *d.only_for_task != config.task.kind) continue;
      if (d.printed_if && !d.printed_if(config)) continue;
      if (section == d.section) keys += std::string(d.key) + " = " + value_text(d) + "\n";
    }
    // A section whose keys are all left out (the flat [terrain]) leaves no header either.
    if (!keys.empty()) out += "[" + section + "]\n" + keys;
  }
  return out;
}

std::uint64_t text_hash(const std::string& text) {
  return fnv1a64(text);
}

std::uint64_t config_hash(const Config& config) {
  return text_hash(canonical_text(config));
}

std::string experiment_text(const std::string& canonical_config_text) {
  // Canonical text has one "key = value" line per key under its "[section]" line; the lines of
  // run.generations and run.seed are left out.
  std::string out;
  std::string section;
  std::size_t begin = 0;
  while (begin < canonical_config_text.size()) {
    std::size_t end = canonical_config_text.find('\n', begin);
    end = end == std::string::npos ? canonical_config_text.size() : end + 1;
    const std::string_view line(canonical_config_text.data() + begin, end - begin);
    if (line.starts_with("[")) section = std::string(line.substr(0, line.find(']') + 1));
    const bool run_identity_only =
        section == "[run]" && (line.starts_with("generations = ") || line.starts_with("seed = "));
    if (!run_identity_only) out.append(line);
    begin = end;
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> canonical_entries(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> entries;
  std::string section;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with("[")) {
      section = line.substr(1, line.find(']') - 1);
      continue;
    }
    const std::size_t eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    entries.emplace_back(section + "." + line.substr(0, eq), line.substr(eq + 3));
  }
  return entries;
}

std::vector<KeyDifference> config_differences(const std::string& first, const std::string& second) {
  const auto a = canonical_entries(first);
  const auto b = canonical_entries(second);
  const auto find = [](const auto& entries, const std::string& key) -> const std::string* {
    for (const auto& [k, v] : entries)
      if (k == key) return &v;
    return nullptr;
  };
  std::vector<KeyDifference> out;
  for (const auto& [key, value] : a) {
    const std::string* other = find(b, key);
    if (other == nullptr || *other != value) out.push_back({key, value, other ? *other : ""});
  }
  for (const auto& [key, value] : b)
    if (find(a, key) == nullptr) out.push_back({key, "", value});
  return out;
}

std::uint64_t experiment_hash_of_text(const std::string& canonical_config_text) {
  return text_hash(experiment_text(canonical_config_text));
}

std::uint64_t experiment_hash(const Config& config) {
  return experiment_hash_of_text(canonical_text(config));
}

std::string hash_hex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

std::vector<StructuralMaterial> material_table(const PhysicsConfig& physics) {
  // numpy.linspace(E_min, E_max, count): start + k*step, last value exactly E_max.
  const auto count = static_cast<int>(physics.material_count);
  std::vector<StructuralMaterial> table(count);
  const double step =
      count > 1 ? (physics.youngs_modulus_max - physics.youngs_modulus_min) / (count - 1) : 0.0;
  for (int k = 0; k < count; ++k) {
    table[k].youngs_modulus = (k == count - 1 && count > 1) ? physics.youngs_modulus_max
                                                            : physics.youngs_modulus_min + k * step;
    table[k].density = physics.density;
  }
  return table;
}

const std::vector<TaskKind>& task_kinds() {
  static const std::vector<TaskKind> kinds = {TaskKind::gait, TaskKind::directed, TaskKind::rotate};
  return kinds;
}

const char* to_string(TaskKind kind) {
  switch (kind) {
    case TaskKind::gait:
      return "gait";
    case TaskKind::directed:
      return "directed";
    case TaskKind::rotate:
      return "rotate";
  }
  return "unknown";
}

std::optional<TaskKind> task_kind_from_string(const std::string& name) {
  for (TaskKind k : task_kinds())
    if (name == to_string(k)) return k;
  return std::nullopt;
}

std::string experiment_name(const Config& config) {
  // Controller learning is another experiment (docs/model.md §8.11): "gait-closed-learn".
  const std::string learn = learning_on(config) ? "-learn" : "";
  const TerrainConfig& t = config.terrain;
  if (t.kind == GroundKind::flat) return experiment_name(config.task) + learn;
  const std::string kind =
      config.task.kind == TaskKind::directed ? "dir" : to_string(config.task.kind);
  return kind + (t.kind == GroundKind::rows ? "-rows-" : "-rough-") +
         to_string(config.task.control) + learn;
}

std::string experiment_name(const TaskConfig& task) {
  // "dir" is the thesis' short name of the directed experiments (run names mdv2_*, §8.9).
  const std::string kind = task.kind == TaskKind::directed ? "dir" : to_string(task.kind);
  return kind + "-" + to_string(task.control);
}

}  // namespace softevo
