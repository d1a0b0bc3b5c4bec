// Resolved run configuration: plain data shared by every module.
//
// Configs are TOML files (configs/*.toml) parsed strictly by load_config(): an unknown section or
// key, a wrong type or an out-of-range value is a ConfigError naming file, line, key and the
// allowed values. Everything inside the code is SI; pressures enter in bar and are converted to
// Pa here, at the config boundary (docs/model.md §1). Key names follow neat-python where the
// thesis parameter has one. Defaults are the thesis experiment values of
// docs/model.md §1 and §8.8.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/body_plan.hpp"
#include "common/choice.hpp"
#include "common/terrain_shape.hpp"

namespace softevo {

// The choices of the config (common/choice.hpp), in the order of their config names.
enum class FailurePolicy : std::uint8_t { killed, abort };         // run.on_failure
enum class ControlLoop : std::uint8_t { open, closed };            // task.control (§4.1)
enum class Integrator : std::uint8_t { pneuvox, symplectic };      // physics.integrator (§2.9)
enum class GroundKind : std::uint8_t { flat, rows, heightfield };  // terrain.kind (§2.8a)
enum class TerrainResample : std::uint8_t { per_run, per_generation, per_evaluation };
enum class SupplyScaling : std::uint8_t { none, inverse_volume };                      // (§3.8)
enum class CrossoverMethod : std::uint8_t { one_point_per_layer, random, one_point };  // (§8.6)
enum class ControllerInit : std::uint8_t { random, oscillator };   // (§8.2, §4.8)
enum class DistanceInput : std::uint8_t { center, pneuvox };       // (§6.2)
enum class LearningMethod : std::uint8_t { none, es };             // (§8.11)
enum class Inheritance : std::uint8_t { lamarckian, baldwinian };  // (§8.11)
enum class SearchKind : std::uint8_t { neat, map_elites, afpo };   // (§8.12)
enum class AfpoAge : std::uint8_t { lineage, body };               // (§8.12.3)

template <>
struct ChoiceNames<FailurePolicy> {
  static constexpr std::array<const char*, 2> names = {"killed", "abort"};
};
template <>
struct ChoiceNames<ControlLoop> {
  static constexpr std::array<const char*, 2> names = {"open", "closed"};
};
template <>
struct ChoiceNames<Integrator> {
  static constexpr std::array<const char*, 2> names = {"pneuvox", "symplectic"};
};
template <>
struct ChoiceNames<GroundKind> {
  static constexpr std::array<const char*, 3> names = {"flat", "rows", "heightfield"};
};
template <>
struct ChoiceNames<HeightfieldKind> {
  static constexpr std::array<const char*, 3> names = {"bumps", "steps", "slope"};
};
template <>
struct ChoiceNames<TerrainResample> {
  static constexpr std::array<const char*, 3> names = {"per_run", "per_generation",
                                                       "per_evaluation"};
};
template <>
struct ChoiceNames<SupplyScaling> {
  static constexpr std::array<const char*, 2> names = {"none", "inverse_volume"};
};
template <>
struct ChoiceNames<CrossoverMethod> {
  static constexpr std::array<const char*, 3> names = {"1pointpl", "random", "1point"};
};
template <>
struct ChoiceNames<ControllerInit> {
  static constexpr std::array<const char*, 2> names = {"random", "oscillator"};
};
template <>
struct ChoiceNames<DistanceInput> {
  static constexpr std::array<const char*, 2> names = {"center", "pneuvox"};
};
template <>
struct ChoiceNames<LearningMethod> {
  static constexpr std::array<const char*, 2> names = {"none", "es"};
};
template <>
struct ChoiceNames<Inheritance> {
  static constexpr std::array<const char*, 2> names = {"lamarckian", "baldwinian"};
};
template <>
struct ChoiceNames<SearchKind> {
  static constexpr std::array<const char*, 3> names = {"neat", "map_elites", "afpo"};
};
template <>
struct ChoiceNames<AfpoAge> {
  static constexpr std::array<const char*, 2> names = {"lineage", "body"};
};

struct RunConfig {
  std::int64_t seed = 1;           // run seed; every evaluation seed derives from it
  std::int64_t generations = 500;  // generations to evaluate
  // Wall-clock limit of one evaluation [s]; 0 = no wall-clock limit (the step limits of
  // physics/work_limits.hpp still bound every evaluation). A timeout is a status, not a crash.
  double eval_timeout_seconds = 600.0;
  // What a worker-side failure (exception, non-finite state, timeout) scores: "killed" scores it
  // like a killed robot (fitness 0) and the run goes on; "abort" ends the run with an error.
  FailurePolicy on_failure = FailurePolicy::killed;
  // The run stops (exit code 1, the cause printed and recorded as the archive's stop_reason)
  // after this many generations in a row in which no evaluation succeeded: each one diverged,
  // failed, timed out or had an invalid body (a config that cannot work, not evolution). The
  // default stops at the first such generation (generation 0 included); 0 = never stop.
  std::int64_t stop_after_failed_generations = 1;
};

// The task a run evolves robots for (§7). Parsed once, here at the config boundary; the rest of
// the code asks the task's module (tasks/task.hpp) and never tests the kind.
enum class TaskKind : std::uint8_t {
  gait,      // forward locomotion along +x (§7.1)
  directed,  // locomotion towards each of task.directions (§7.2-§7.4)
  rotate,    // in-place rotation about +z (§7.6)
};
template <>
struct ChoiceNames<TaskKind> {
  static constexpr std::array<const char*, 3> names = {"gait", "directed", "rotate"};
};
// Every kind in enum order (to_string and choice_names<TaskKind> give the config names).
const std::vector<TaskKind>& task_kinds();

struct TaskConfig {
  TaskKind kind = TaskKind::gait;
  ControlLoop control = ControlLoop::open;  // closed: pressure sensors as inputs (§4.1)
  double eval_seconds = 10.0;  // nominal evaluation length [s]; frames = round(60 * seconds)
  double control_rate = 60.0;  // controller rate [Hz] (§4.6)
  // Target directions of the directed task [deg], in the order the thesis summed them (§7.4).
  std::vector<double> directions = {0.0, -40.0, -20.0, 20.0, 40.0};
  double path_penalty_weight = 0.1;  // omega of §7.2
  // Rotate task (§7.6): fitness lost per body length of horizontal centroid travel
  // [rad / body length].
  double rotate_travel_penalty = 1.0;
};

struct PhysicsConfig {
  Integrator integrator = Integrator::pneuvox;  // pneuvox (§2.12-2.13) or symplectic (§2.9)
  double dt_fraction = 1.0;        // time step = recommended step (§2.14) x dt_fraction
  double voxel_size = 0.01;        // voxel edge [m]
  double gravity = 9.80665;        // [m/s^2], acting along -z
  bool floor = true;               // floor contact at z = 0 (voxel centres, §2.8)
  bool self_collision = true;      // voxel-voxel collisions (§2.10)
  double static_friction = 0.9;    // mu_s [-]
  double kinetic_friction = 0.9;   // mu_k [-]
  double internal_damping = 0.1;   // zeta_int [-] (bond damping ratio)
  double global_damping = 0.001;   // zeta_glob [-]
  double collision_damping = 0.1;  // zeta_col [-]
  // Structural material k (1..material_count) has E_k = linspace(min, max, count)[k-1] (§1).
  double youngs_modulus_min = 1.0e4;  // [Pa]
  double youngs_modulus_max = 1.0e5;  // [Pa]
  std::int64_t material_count = 10;
  double density = 1000.0;  // [kg/m^3]
};

// The ground (docs/model.md §2.8a). Flat by default; every other kind's keys enter the
// canonical text (and the config hash) only when kind is not "flat", so the configs of every
// existing archive keep their hash.
struct TerrainConfig {
  GroundKind kind = GroundKind::flat;  // flat, rows (the thesis system's fixed voxels), heightfield
  HeightfieldKind heightfield = HeightfieldKind::bumps;  // kind = heightfield: bumps, steps, slope
  // kind = heightfield: its numbers (common/terrain_shape.hpp), at the config's defaults.
  TerrainShape shape{.amplitude = 0.01,
                     .correlation_length = 0.05,
                     .step_height = 0.005,
                     .step_spacing = 0.05,
                     .slope_angle = 10.0,
                     .slope_direction = 0.0};
  std::int64_t seed = 1;  // terrain seed, mixed with run.seed
  // How often the ground is drawn anew: once per run, per generation (every genome of a
  // generation on the same ground), or per evaluation (genome and direction too).
  TerrainResample resample = TerrainResample::per_run;

  // The ids an evaluation's ground is drawn from (docs/model.md §2.8a "Seeds and resampling"):
  // none on flat ground; the generation unless resample = per_run; the genome id and work unit
  // too with per_evaluation. The worker seeds the ground by these (worker::terrain_params) and
  // the master shares a result only between evaluations they do not tell apart
  // (master::reuse_scope).
  bool ground_varies_with_generation() const {
    return kind != GroundKind::flat && resample != TerrainResample::per_run;
  }
  bool ground_varies_with_evaluation() const {
    return kind != GroundKind::flat && resample == TerrainResample::per_evaluation;
  }
};

// Median rest volume of the 57 chambers of the 40 thesis champions [m^3] (about 133 cm^3;
// docs/model.md §3.8): the default reference volume of pneumatics.supply_pressure_scaling =
// "inverse_volume". Recomputed from the thesis champions by tests/physics/test_pneumatics.cpp.
inline constexpr double kThesisMedianChamberVolume = 1.3299984857439995e-4;

struct PneumaticsConfig {
  double supply_pressure = 1.2e5;   // inlet reservoir, absolute [Pa] (config: bar)
  double ambient_pressure = 1.0e5;  // outlet reservoir, absolute [Pa] (config: bar)
  double conductivity = 0.025;      // conduit conductivity scale [m^3/(bar s)] (§3.5)
  double valve_cutoff = 10.0;       // low-pass cut-off of the valve opening [Hz] (§3.5)
  std::int64_t valve_filter_stages = 4;
  double valve_filter_q = 0.707;
  // First-frame pressure sensor reading, absolute [Pa] (config: bar; §3.7, default 0.0 bar).
  double initial_sensor_pressure = 0.0;
  // Thesis 5.3.4: "none" gives every inlet supply_pressure; "inverse_volume" raises the supply's
  // gauge pressure (above ambient_pressure) of each chamber in inverse proportion to its rest
  // volume, so small actuators are compensated (docs/model.md §3.8).
  SupplyScaling supply_pressure_scaling = SupplyScaling::none;
  // Rest volume [m^3] whose chamber keeps supply_pressure under "inverse_volume" (§3.8).
  double scaling_reference_volume = kThesisMedianChamberVolume;
  // Upper bound of a scaled chamber supply, absolute [Pa] (config: bar; §3.8).
  double max_supply_pressure = 2.0e5;
};

struct ControllerConfig {
  std::int64_t hidden = 4;  // Elman hidden (= context) units (§4.1)
  CrossoverMethod crossover_method = CrossoverMethod::one_point_per_layer;  // (§8.6)
  double weight_init_sd = 3.0;       // init SD of genes and initial step size (§8.2)
  double gene_limit = 5.0;           // genes and step sizes clipped to +-gene_limit
  double freq_min = 1.0;             // oscillator frequency range [Hz]
  double freq_max = 5.0;             // [Hz]
  double freq_step_size_init = 0.2;  // initial step size of the frequency gene [Hz]
  // Thesis 5.3.4 and 5.1.1: false removes the sin/cos oscillator inputs (closed loop only, §4.1).
  bool oscillator_inputs = true;
  // Initial controller genes (§8.2): "random", or "oscillator", a hand-made pressure-driven
  // oscillator per chamber (closed loop only, §4.8).
  ControllerInit init = ControllerInit::random;
  // "oscillator": SD of the Gaussian perturbation of every hand-made gene, and the genes' initial
  // mutation step size (§4.8).
  double init_perturbation_sd = 0.1;
};

struct BodyConfig {
  std::vector<std::int64_t> lattice = {10, 10, 10};      // CPPN query lattice X, Y, Z
  DistanceInput distance_input = DistanceInput::center;  // (§6.2)
  double presence_threshold = 0.1;
  double pneumatic_threshold = 0.1;
  std::int64_t max_chambers = 10;  // chambers beyond this stay unactuated voids (§6.5 step 9)
};

// neat-python 0.92 names and semantics (§8.8).
struct NeatConfig {
  std::int64_t pop_size = 50;
  double compatibility_threshold = 3.5;
  double compatibility_disjoint_coefficient = 2.0;
  double compatibility_weight_coefficient = 1.0;
  double conn_add_prob = 0.0713;
  double conn_delete_prob = 0.03;
  double node_add_prob = 0.05;
  double node_delete_prob = 0.0;
  std::string activation_default = "random";
  double activation_mutate_rate = 0.01;
  std::vector<std::string> activation_options = {"sigmoid", "sin",     "abs",  "square",
                                                 "exp",     "clamped", "gauss"};
  double bias_init_mean = 0.0;
  double bias_init_stdev = 1.0;
  double bias_max_value = 3.0;
  double bias_min_value = -3.0;
  double bias_mutate_power = 0.0025;
  double bias_mutate_rate = 0.5;
  double bias_replace_rate = 0.0;
  double weight_init_mean = 0.0;
  double weight_init_stdev = 1.0;
  double weight_max_value = 3.0;
  double weight_min_value = -3.0;
  double weight_mutate_power = 0.0025;
  double weight_mutate_rate = 0.5;
  double weight_replace_rate = 0.0;
  double response_init_mean = 1.0;
  double response_init_stdev = 0.0;
  double response_max_value = 30.0;
  double response_min_value = -30.0;
  double response_mutate_power = 0.0;
  double response_mutate_rate = 0.0;
  double response_replace_rate = 0.0;
  double enabled_mutate_rate = 0.01;
  std::int64_t max_stagnation = 15;
  std::int64_t species_elitism = 1;
  std::int64_t elitism = 1;
  double survival_threshold = 1.0;
  std::int64_t tournament_size = 2;
  std::int64_t min_species_size = 2;
};

// Controller learning inside a run (docs/model.md §8.11, thesis 5.3.6): every body that is new
// in its generation learns its controller with a (1+lambda) evolution strategy before selection
// sees it. method = "none" (the thesis, the default) leaves every [learning] key out of the
// canonical text, so configs without learning keep their config hash and their bits.
struct LearningConfig {
  LearningMethod method = LearningMethod::none;
  // Evaluations per new body, the inherited controller's own evaluation included: the strategy
  // runs (evaluations - 1) / population iterations of `population` candidates each.
  std::int64_t evaluations = 101;
  std::int64_t population = 10;  // lambda: candidates per iteration
  // "lamarckian": the learned controller (values and step sizes) replaces the genome's before
  // reproduction; "baldwinian": only the learned fitness counts, the genome reproduces as born.
  Inheritance inheritance = Inheritance::lamarckian;
  // The strategy's step sizes are the genome's (evolution's: weight_init_sd = 3 at first, one
  // large mutation per generation) times this factor: a local search needs small steps.
  double step_size_factor = 0.1;
  // Factor on neat.weight_mutate_power and neat.bias_mutate_power (the CPPN, i.e. the body):
  // the thesis cut them 20-fold so that mutated bodies keep working with their inherited
  // controllers (thesis 3.3, 5.3.5); with learning, 20 restores the uncut strength.
  double body_mutate_power_factor = 1.0;
};

// The search strategy of a run (docs/model.md §8.12, thesis 5.3.4-5.3.5): who selects and
// reproduces each generation. "neat" (the thesis' speciation, the default) leaves [search],
// [map_elites] and [afpo] out of the canonical text, so every existing config keeps its hash;
// each other strategy's keys apply to it alone (an error to set for another strategy).
struct SearchConfig {
  SearchKind strategy = SearchKind::neat;
};

// MAP-Elites (§8.12.2): a grid over 1-3 named descriptors (common/map_grid.hpp), each with its
// range [min, max) and number of bins; the batch of each generation is neat.pop_size.
struct MapElitesConfig {
  std::vector<std::string> descriptors = {"chamber_count", "actuated_fraction"};
  std::vector<double> min = {0.5, 0.0};   // per descriptor, in its unit (§8.12.2)
  std::vector<double> max = {10.5, 1.0};  // per descriptor, > min
  std::vector<std::int64_t> bins = {10, 10};
  std::int64_t max_cells = 10000;  // the grid's cells (product of bins) may not exceed this
  // Probability that an offspring is crossover(A, B) + mutation of two uniformly drawn elites
  // instead of a mutated copy of one.
  double crossover_probability = 0.0;
  // qd_score = sum over elites of (fitness - qd_offset), in the task's fitness unit.
  double qd_offset = 0.0;
};

// Age-fitness Pareto optimisation (§8.12.3): neat.pop_size survivors, each generation
// pop_size - 1 mutated offspring and one random newcomer.
struct AfpoConfig {
  AfpoAge age = AfpoAge::lineage;  // "body": age restarts when a mutation changes the body
};

struct Config {
  RunConfig run;
  TaskConfig task;
  PhysicsConfig physics;
  TerrainConfig terrain;
  PneumaticsConfig pneumatics;
  ControllerConfig controller;
  BodyConfig body;
  NeatConfig neat;
  LearningConfig learning;
  SearchConfig search;
  MapElitesConfig map_elites;
  AfpoConfig afpo;
};

// A config problem: message already names file, line, key and the allowed values.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The shape a config text may have, checked before TOML parsing (a ConfigError naming the line
// otherwise): no config needs more, and a parser's or an error report's cost then stays bounded
// whatever the input (a 50,000-digit number or an inline table 10,000 deep crashed every reader
// through the stack, issue 39). --set values get the same limits.
inline constexpr std::size_t kMaxConfigLineBytes = 10000;
inline constexpr int kMaxConfigNesting = 8;  // arrays and inline tables inside one another

// Where overrides come from, for their error messages: "--set neat.pop_size=4: ..." on the
// command line, 'overrides["neat.pop_size"] = 4: ...' from Python (issue 39).
enum class OverrideOrigin { command_line, python };

// Parse a TOML file strictly, then apply overrides "section.key=value" (TOML value syntax; a bare
// word is taken as a string). Throws ConfigError.
Config load_config(const std::string& path, const std::vector<std::string>& overrides = {},
                   OverrideOrigin origin = OverrideOrigin::command_line);
// Same from TOML text; `source_name` is used in error messages.
Config parse_config(const std::string& toml_text, const std::string& source_name,
                    const std::vector<std::string>& overrides = {},
                    OverrideOrigin origin = OverrideOrigin::command_line);

// `base` with overrides applied and checked like those of parse_config (a value set by a command
// option, e.g. `render --seconds`, gets the config's range check). Throws ConfigError.
Config apply_overrides(const Config& base, const std::vector<std::string>& overrides);
// `v` as a TOML value for an override: shortest round trip; nan and inf as TOML spells them.
std::string toml_number(double v);

// Every key in schema order, one per line, shortest round-trip numbers, pressures in bar.
// Parsing this text gives back an identical Config.
std::string canonical_text(const Config& config);
// FNV-1a 64 of canonical_text(): the config identity in archives and on the wire.
std::uint64_t config_hash(const Config& config);
std::string hash_hex(std::uint64_t hash);  // 16 lower-case hex digits

// Structural materials 1..material_count of the thesis: E_k = linspace(E_min, E_max, count)
// (numpy semantics, docs/model.md §1/§6.4), density as configured. Index k-1 = material k.
std::vector<StructuralMaterial> material_table(const PhysicsConfig& physics);
// "gait-open", "dir-closed", "rotate-open", ... from task.kind and task.control.
std::string experiment_name(const TaskConfig& task);
// The same with the ground when it is not flat: "gait-rough-open" (terrain.kind =
// "heightfield"), "gait-rows-closed" (terrain.kind = "rows"); flat configs keep their name;
// with controller learning "-learn" follows ("gait-closed-learn", docs/model.md §8.11).
std::string experiment_name(const Config& config);

}  // namespace softevo
