// The rows of the config schema (common/config_schema.hpp).
#include "common/config_schema.hpp"

#include <algorithm>
#include <string_view>
#include <type_traits>

#include "common/map_grid.hpp"

namespace softevo::config_schema {

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
bool learning_on(const Config& c) {
  return c.learning.method != LearningMethod::none;
}
bool supply_scaled(const Config& c) {
  return c.pneumatics.supply_pressure_scaling != SupplyScaling::none;
}
bool search_map_elites(const Config& c) {
  return c.search.strategy == SearchKind::map_elites;
}
bool search_afpo(const Config& c) {
  return c.search.strategy == SearchKind::afpo;
}

namespace {

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
bool oscillator_inputs_removed(const Config& c) {
  return !c.controller.oscillator_inputs;
}
bool controller_init_not_random(const Config& c) {
  return c.controller.init != ControllerInit::random;
}

bool search_not_neat(const Config& c) {
  return c.search.strategy != SearchKind::neat;
}
constexpr const char* kMapElitesOnly = "search.strategy = \"map_elites\"";

}  // namespace

std::vector<std::string> allowed_strings(const KeyDef& def) {
  return std::visit(
      [&](auto* target) -> std::vector<std::string> {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (ConfigChoice<T>) {
          return choice_names<T>();
        } else {
          return def.allowed;
        }
      },
      def.target);
}

const std::vector<std::string> kSections = {"run",        "task",       "physics",    "terrain",
                                            "pneumatics", "controller", "body",       "neat",
                                            "learning",   "search",     "map_elites", "afpo"};

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
  auto& me = c.map_elites;
  std::vector<KeyDef> rows = {
      {.section = "run", .key = "seed", .target = &r.seed, .min = 0, .max = 9.0e15},
      {.section = "run", .key = "generations", .target = &r.generations, .min = 0, .max = 1.0e7},
      {.section = "run",
       .key = "eval_timeout_seconds",
       .target = &r.eval_timeout_seconds,
       .min = 0,
       .max = 1.0e7,  // 116 days; near 9.2e9 s a deadline overflowed the clock (issue 39)
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

      // Search strategies (§8.12): each strategy's keys apply to it alone.
      {.section = "search",
       .key = "strategy",
       .target = &c.search.strategy,
       .printed_if = search_not_neat},
      only_when({.section = "map_elites",
                 .key = "descriptors",
                 .target = &me.descriptors,
                 .allowed = map_descriptor_names()},
                search_map_elites, kMapElitesOnly),
      only_when({.section = "map_elites", .key = "min", .target = &me.min}, search_map_elites,
                kMapElitesOnly),
      only_when({.section = "map_elites", .key = "max", .target = &me.max}, search_map_elites,
                kMapElitesOnly),
      only_when({.section = "map_elites", .key = "bins", .target = &me.bins, .min = 1, .max = 1e9},
                search_map_elites, kMapElitesOnly),
      only_when({.section = "map_elites",
                 .key = "max_cells",
                 .target = &me.max_cells,
                 .min = 1,
                 .max = 1e7},
                search_map_elites, kMapElitesOnly),
      only_when({.section = "map_elites",
                 .key = "crossover_probability",
                 .target = &me.crossover_probability,
                 .min = 0,
                 .max = 1},
                search_map_elites, kMapElitesOnly),
      only_when({.section = "map_elites", .key = "qd_offset", .target = &me.qd_offset},
                search_map_elites, kMapElitesOnly),
      only_when({.section = "afpo", .key = "age", .target = &c.afpo.age}, search_afpo,
                "search.strategy = \"afpo\""),
  };
  // The heightfield's numbers follow terrain.heightfield: their place in the canonical text.
  const auto heightfield = std::find_if(rows.begin(), rows.end(), [](const KeyDef& def) {
    return std::string_view(def.section) == "terrain" && std::string_view(def.key) == "heightfield";
  });
  const std::vector<KeyDef> shape = terrain_shape_rows(tr.shape);
  rows.insert(heightfield + 1, shape.begin(), shape.end());
  return rows;
}

}  // namespace softevo::config_schema
