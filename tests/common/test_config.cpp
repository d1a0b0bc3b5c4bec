// Strict config parsing: defaults, overrides, canonical text and hash, and a folder of
// deliberately broken configs (tests/data/bad_configs), each carrying its exact expected error
// on its first line ("# expect: ...").
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/config.hpp"

namespace softevo {
namespace fs = std::filesystem;

// Parsing `text` (as file `file`) fails with a ConfigError whose message contains `needle`.
static void expect_config_error(const std::string& text, const std::string& file,
                                const std::string& needle) {
  try {
    parse_config(text, file);
    ADD_FAILURE() << "expected an error for " << text;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

static fs::path source_dir() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  return env ? fs::path(env) : fs::current_path();
}

TEST(Config, DefaultsAreTheThesisValues) {
  const Config c = parse_config("", "empty.toml");
  EXPECT_EQ(c.neat.pop_size, 50);
  EXPECT_DOUBLE_EQ(c.neat.compatibility_threshold, 3.5);
  EXPECT_DOUBLE_EQ(c.neat.conn_add_prob, 0.0713);
  EXPECT_EQ(c.physics.integrator, Integrator::pneuvox);
  EXPECT_DOUBLE_EQ(c.pneumatics.supply_pressure, 1.2e5);  // bar converted to Pa
  EXPECT_DOUBLE_EQ(c.pneumatics.initial_sensor_pressure, 0.0);
  EXPECT_EQ(c.task.directions.size(), 5u);
}

TEST(Config, BarIsConvertedToPascalAtTheBoundary) {
  const Config c = parse_config("[pneumatics]\nsupply_pressure = 1.5\n", "p.toml");
  EXPECT_DOUBLE_EQ(c.pneumatics.supply_pressure, 1.5e5);
  EXPECT_NE(canonical_text(c).find("supply_pressure = 1.5\n"), std::string::npos);
}

TEST(Config, OverridesApplyAfterTheFileAndAreValidated) {
  const Config c = parse_config("[neat]\npop_size = 20\n", "o.toml",
                                {"neat.pop_size=30", "physics.integrator=symplectic",
                                 "task.directions=[0, 90]", "physics.self_collision=false"});
  EXPECT_EQ(c.neat.pop_size, 30);
  EXPECT_EQ(c.physics.integrator, Integrator::symplectic);
  EXPECT_EQ(c.task.directions, (std::vector<double>{0, 90}));
  EXPECT_FALSE(c.physics.self_collision);
  try {
    parse_config("", "o.toml", {"neat.pop_size=1"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--set neat.pop_size=1: neat.pop_size = 1 is out of range; allowed: integer in "
              "[2, 1000000]");
  }
  EXPECT_THROW(parse_config("", "o.toml", {"neat.pop_size"}), ConfigError);
  EXPECT_THROW(parse_config("", "o.toml", {"nope.key=1"}), ConfigError);
}

TEST(Config, CanonicalTextRoundTripsAndHashIsStable) {
  const Config c = parse_config("[run]\nseed = 7\n[physics]\ndt_fraction = 0.3\n", "c.toml");
  const std::string text = canonical_text(c);
  const Config again = parse_config(text, "canonical");
  EXPECT_EQ(canonical_text(again), text);
  EXPECT_EQ(config_hash(again), config_hash(c));
  EXPECT_EQ(hash_hex(config_hash(c)).size(), 16u);
  // Any change of a value changes the hash.
  EXPECT_NE(config_hash(parse_config("[run]\nseed = 8\n", "x")), config_hash(c));
  // Formatting differences (comments, order, int vs float spelling) do not.
  EXPECT_EQ(config_hash(parse_config("# c\n[physics]\ndt_fraction = 0.30\n[run]\nseed=7\n", "y")),
            config_hash(c));
}

TEST(Config, HashOfDefaultsIsPinned) {
  // The hash is archived with every run; changing the canonical form or a default changes it.
  // Update this value deliberately (and say why in the commit) when the schema changes.
  EXPECT_EQ(hash_hex(config_hash(Config{})), "33eaaf9fe334a91f");
}

TEST(Config, TaskKindIsParsedOnceAndItsKeysBelongToIt) {
  const Config rotate =
      parse_config("[task]\nkind = \"rotate\"\nrotate_travel_penalty = 2.5\n", "r");
  EXPECT_EQ(rotate.task.kind, TaskKind::rotate);
  EXPECT_EQ(rotate.task.rotate_travel_penalty, 2.5);
  EXPECT_EQ(experiment_name(rotate.task), "rotate-open");
  EXPECT_EQ(experiment_name(parse_config("[task]\nkind = \"directed\"\n", "d").task), "dir-open");
  // A task's own key is in the canonical text (and the hash) of that task only, so the hash of
  // every other task's config stays what it was before the key existed.
  const std::string text = canonical_text(rotate);
  EXPECT_NE(text.find("rotate_travel_penalty = 2.5\n"), std::string::npos) << text;
  EXPECT_EQ(canonical_text(parse_config(text, "canonical")), text);
  EXPECT_EQ(canonical_text(Config{}).find("rotate_travel_penalty"), std::string::npos);
  // Setting it for another task is an error naming the key, the task and where it was set.
  try {
    parse_config("[task]\nkind = \"gait\"\n", "g.toml", {"task.rotate_travel_penalty=1"});
    FAIL() << "expected an error";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("--set task.rotate_travel_penalty=1"), std::string::npos) << m;
    EXPECT_NE(m.find("applies to task.kind = \"rotate\" only"), std::string::npos) << m;
  }
  // The allowed kinds are listed for a typo.
  try {
    parse_config("[task]\nkind = \"rotat\"\n", "t.toml");
    FAIL() << "expected an error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("\"rotate\""), std::string::npos) << e.what();
  }
}

// [terrain] (docs/model.md §2.8a): flat leaves the canonical text (and so every existing
// config hash) as it was; another kind prints its own keys only; a key of another kind is an
// error naming it.
TEST(Config, TerrainKeysEnterTheTextOnlyOffFlatGround) {
  EXPECT_EQ(canonical_text(Config{}).find("[terrain]"), std::string::npos);
  EXPECT_EQ(config_hash(parse_config("[terrain]\nkind = \"flat\"\n", "f")), config_hash(Config{}));
  const Config rough = parse_config(
      "[terrain]\nkind = \"heightfield\"\nheightfield = \"bumps\"\namplitude = 0.02\n"
      "resample = \"per_generation\"\n",
      "r.toml");
  EXPECT_EQ(rough.terrain.shape.amplitude, 0.02);
  const std::string text = canonical_text(rough);
  EXPECT_NE(text.find("[terrain]\nkind = \"heightfield\"\nheightfield = \"bumps\"\n"
                      "amplitude = 0.02\ncorrelation_length = 0.05\nseed = 1\n"
                      "resample = \"per_generation\"\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("step_height"), std::string::npos) << "a key of another height field";
  EXPECT_EQ(canonical_text(parse_config(text, "canonical")), text);
  EXPECT_EQ(experiment_name(rough), "gait-rough-open");
  EXPECT_EQ(experiment_name(parse_config("[terrain]\nkind = \"rows\"\n[task]\ncontrol = "
                                         "\"closed\"\n",
                                         "rows")),
            "gait-rows-closed");
  EXPECT_EQ(experiment_name(Config{}), "gait-open");
  for (const auto& [text_in, needle] :
       {std::pair<std::string, std::string>{
            "[terrain]\namplitude = 0.01\n",
            "terrain.amplitude applies only when terrain.kind = \"heightfield\" and"},
        {"[terrain]\nkind = \"rows\"\nslope_angle = 5\n", "terrain.slope_angle applies only"},
        {"[terrain]\nkind = \"hills\"\n", "\"heightfield\""},
        {"[terrain]\nkind = \"heightfield\"\nheightfield = \"slope\"\nslope_angle = 70\n",
         "out of range"},
        {"[terrain]\nkind = \"rows\"\nresample = \"sometimes\"\n", "per_evaluation"},
        // Ground that cannot work is refused here, not found out by every evaluation failing.
        {"[terrain]\nkind = \"heightfield\"\nheightfield = \"steps\"\nstep_spacing = 0.005\n",
         "terrain.step_spacing = 0.005 m must be at least one voxel (physics.voxel_size = 0.01 m)"},
        {"[terrain]\nkind = \"heightfield\"\nheightfield = \"bumps\"\n"
         "correlation_length = 1e-15\n",
         "terrain.correlation_length = 1e-15 m must be at least one voxel"}}) {
    expect_config_error(text_in, "t.toml", needle);
  }
}

// Controller learning (docs/model.md §8.11): off by default and then absent from the text (every
// existing config hash stays), its keys settable only with a method, its budget checked.
TEST(Config, LearningKeysEnterTheTextOnlyWithAMethod) {
  EXPECT_EQ(canonical_text(Config{}).find("[learning]"), std::string::npos);
  EXPECT_EQ(config_hash(parse_config("[learning]\nmethod = \"none\"\n", "n")),
            config_hash(Config{}));
  const Config learn = parse_config(
      "[learning]\nmethod = \"es\"\nevaluations = 51\npopulation = 5\n"
      "inheritance = \"baldwinian\"\nstep_size_factor = 0.2\nbody_mutate_power_factor = 20.0\n",
      "l.toml");
  EXPECT_EQ(learn.learning.evaluations, 51);
  EXPECT_EQ(learn.learning.population, 5);
  EXPECT_EQ(learn.learning.inheritance, Inheritance::baldwinian);
  EXPECT_EQ(learn.learning.step_size_factor, 0.2);
  const std::string text = canonical_text(learn);
  EXPECT_NE(text.find("[learning]\nmethod = \"es\"\nevaluations = 51\npopulation = 5\n"
                      "inheritance = \"baldwinian\"\nstep_size_factor = 0.2\n"
                      "body_mutate_power_factor = 20.0\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(canonical_text(parse_config(text, "canonical")), text);
  EXPECT_EQ(experiment_name(learn), "gait-open-learn");
  for (const auto& [text_in, needle] :
       {std::pair<std::string, std::string>{"[learning]\nevaluations = 50\n",
                                            "learning.evaluations applies only when "
                                            "learning.method is not \"none\""},
        {"[learning]\nmethod = \"cma\"\n", "\"es\""},
        {"[learning]\nmethod = \"es\"\ninheritance = \"darwinian\"\n", "\"baldwinian\""},
        {"[learning]\nmethod = \"es\"\nevaluations = 10\npopulation = 10\n",
         "learning.evaluations = 10 must be >= 1 + learning.population = 11"},
        {"[learning]\nmethod = \"es\"\nbudget = 10\n", "unknown key 'learning.budget'"},
        {"[learning]\nmethod = \"es\"\n[terrain]\nkind = \"rows\"\n"
         "resample = \"per_evaluation\"\n",
         "needs terrain.resample"}}) {
    expect_config_error(text_in, "l.toml", needle);
  }
}

// Thesis 5.3.4 options (docs/model.md §3.8, §4.1, §4.8): at their defaults they leave the
// canonical text (so every existing config hash) unchanged; other values print their keys; a
// typo or a value out of range is an error naming the key.
TEST(Config, ActuatorOptionsEnterTheTextOnlyOffTheirDefaults) {
  const std::string defaults = canonical_text(Config{});
  for (const char* key :
       {"supply_pressure_scaling", "scaling_reference_volume", "max_supply_pressure",
        "oscillator_inputs", "\ninit =", "init_perturbation_sd"})
    EXPECT_EQ(defaults.find(key), std::string::npos) << key;
  EXPECT_EQ(config_hash(parse_config("[pneumatics]\nsupply_pressure_scaling = \"none\"\n"
                                     "[controller]\noscillator_inputs = true\ninit = \"random\"\n",
                                     "d.toml")),
            config_hash(Config{}));

  const Config scaled = parse_config(
      "[pneumatics]\nsupply_pressure_scaling = \"inverse_volume\"\nmax_supply_pressure = 1.8\n",
      "s.toml");
  EXPECT_EQ(scaled.pneumatics.max_supply_pressure, 1.8e5);  // bar -> Pa
  EXPECT_EQ(scaled.pneumatics.scaling_reference_volume, kThesisMedianChamberVolume);
  const std::string text = canonical_text(scaled);
  EXPECT_NE(text.find("supply_pressure_scaling = \"inverse_volume\"\n"
                      "scaling_reference_volume = 0.00013299984857439995\n"
                      "max_supply_pressure = 1.8\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(canonical_text(parse_config(text, "canonical")), text);

  const Config oscillator = parse_config(
      "[task]\ncontrol = \"closed\"\n[controller]\noscillator_inputs = false\n"
      "init = \"oscillator\"\n",
      "o.toml");
  EXPECT_FALSE(oscillator.controller.oscillator_inputs);
  const std::string otext = canonical_text(oscillator);
  EXPECT_NE(otext.find("oscillator_inputs = false\ninit = \"oscillator\"\n"
                       "init_perturbation_sd = 0.1\n"),
            std::string::npos)
      << otext;
  EXPECT_EQ(canonical_text(parse_config(otext, "canonical")), otext);

  const std::string closed = "[task]\ncontrol = \"closed\"\n";
  for (const auto& [text_in, needle] :
       {std::pair<std::string, std::string>{
            "[pneumatics]\nsupply_pressure_scaling = \"inverse_volum\"\n",
            "pneumatics.supply_pressure_scaling = \"inverse_volum\" is not allowed (did you "
            "mean 'inverse_volume'?)"},
        {"[pneumatics]\nsupply_pressure_scalng = \"none\"\n",
         "unknown key 'pneumatics.supply_pressure_scalng' (did you mean "
         "'supply_pressure_scaling'?)"},
        {"[pneumatics]\nmax_supply_pressure = 3\n",
         "pneumatics.max_supply_pressure applies only when "
         "pneumatics.supply_pressure_scaling = \"inverse_volume\""},
        {"[pneumatics]\nsupply_pressure_scaling = \"inverse_volume\"\n"
         "max_supply_pressure = 1.1\n",
         "pneumatics.max_supply_pressure = 1.1 bar must be >= pneumatics.supply_pressure"},
        {"[pneumatics]\nsupply_pressure_scaling = \"inverse_volume\"\n"
         "max_supply_pressure = 0\n",
         "pneumatics.max_supply_pressure = 0.0 is out of range; allowed: number in (0.0, 100.0] "
         "bar"},
        {"[pneumatics]\nsupply_pressure_scaling = \"inverse_volume\"\n"
         "scaling_reference_volume = -1e-4\n",
         "pneumatics.scaling_reference_volume = -1e-04 is out of range"},
        {"[pneumatics]\nsupply_pressure_scaling = \"inverse_volume\"\nsupply_pressure = 0.9\n",
         "pneumatics.supply_pressure_scaling = \"inverse_volume\" needs "
         "pneumatics.supply_pressure > pneumatics.ambient_pressure"},
        {closed + "[controller]\ninit = \"oscilator\"\n",
         "controller.init = \"oscilator\" is not allowed (did you mean 'oscillator'?)"},
        {closed + "[controller]\noscillator_inputs = \"no\"\n",
         "controller.oscillator_inputs must be true or false, got a string"},
        {closed + "[controller]\ninit_perturbation_sd = 0.2\n",
         "controller.init_perturbation_sd applies only when controller.init = \"oscillator\""},
        {"[controller]\ninit = \"oscillator\"\n",
         "controller.init = \"oscillator\" needs task.control = \"closed\""},
        {"[controller]\noscillator_inputs = false\n",
         "controller.oscillator_inputs = false needs task.control = \"closed\""}}) {
    expect_config_error(text_in, "a.toml", needle);
  }
}

TEST(Config, MaterialTableIsNumpyLinspace) {
  const auto table = material_table(PhysicsConfig{});
  ASSERT_EQ(table.size(), 10u);
  EXPECT_DOUBLE_EQ(table[0].youngs_modulus, 1e4);
  EXPECT_DOUBLE_EQ(table[4].youngs_modulus, 5e4);
  EXPECT_EQ(table[9].youngs_modulus, 1e5);  // last value exact
  EXPECT_DOUBLE_EQ(table[3].density, 1000.0);
}

TEST(Config, EveryShippedConfigParses) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(source_dir() / "configs")) {
    if (entry.path().extension() != ".toml") continue;
    EXPECT_NO_THROW(load_config(entry.path().string())) << entry.path();
    ++count;
  }
  EXPECT_GT(count, 0);
}

// Command options applied to a resolved config (render --seconds) change only their keys: every
// other value keeps its bits, the pressures converted from bar included.
TEST(Config, ApplyOverridesChangesOnlyTheOverriddenKeys) {
  for (const auto& entry : fs::directory_iterator(source_dir() / "configs")) {
    if (entry.path().extension() != ".toml") continue;
    const Config c = load_config(entry.path().string());
    Config expected = c;
    expected.task.eval_seconds = 2.5;
    const Config o = apply_overrides(c, {"task.eval_seconds=" + toml_number(2.5)});
    EXPECT_EQ(canonical_text(o), canonical_text(expected)) << entry.path();
    const auto same_bits = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
    const PneumaticsConfig &po = o.pneumatics, &pc = c.pneumatics;
    EXPECT_TRUE(same_bits(po.supply_pressure, pc.supply_pressure) &&
                same_bits(po.ambient_pressure, pc.ambient_pressure) &&
                same_bits(po.conductivity, pc.conductivity) &&
                same_bits(po.valve_cutoff, pc.valve_cutoff) &&
                po.valve_filter_stages == pc.valve_filter_stages &&
                same_bits(po.valve_filter_q, pc.valve_filter_q) &&
                same_bits(po.initial_sensor_pressure, pc.initial_sensor_pressure) &&
                po.supply_pressure_scaling == pc.supply_pressure_scaling &&
                same_bits(po.scaling_reference_volume, pc.scaling_reference_volume) &&
                same_bits(po.max_supply_pressure, pc.max_supply_pressure))
        << entry.path();
  }
  EXPECT_THROW(apply_overrides(Config{}, {"task.eval_seconds=" + toml_number(std::nan(""))}),
               ConfigError);
}

TEST(Config, MissingFileIsAClearError) {
  try {
    load_config("/nonexistent/x.toml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/nonexistent/x.toml: cannot open config file: No such file or directory");
  }
}

// On Linux a directory opens as a stream that reads as empty: it used to be a config of all
// defaults, and a full-size run started.
// A robot file or an archive given as a config is named as what it is (issue 39: a robot file
// gave a raw TOML syntax error).
TEST(Config, AFileOfAnotherKindIsNamed) {
  const fs::path dir =
      fs::temp_directory_path() / ("softevo-config-kind-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "robot.json") << "{\"format\": \"softevo.robot/1\"}\n";
  std::ofstream(dir / "run.h5") << "\x89HDF\r\n\x1a\n and more";
  for (const auto& [name, needle] :
       {std::pair{"robot.json", "is a JSON file (a robot file?), not a TOML config"},
        std::pair{"run.h5", "is an HDF5 file (a run archive?), not a TOML config"}}) {
    try {
      load_config((dir / name).string());
      ADD_FAILURE() << name << " loaded";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find("TOML syntax error"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

TEST(Config, DirectoryIsNotAConfigFile) {
  const fs::path dir = fs::temp_directory_path() / "softevo_test_config_dir";
  fs::create_directories(dir);
  try {
    load_config(dir.string());
    ADD_FAILURE() << "a directory was read as a config";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), dir.string() + ": is a directory, not a config file");
  }
  fs::remove_all(dir);
}

// TOML refuses a number beyond a double or an int64 as a syntax error; --set used to take the
// text for a bare string ("got a string"). The error names the key and says out of range.
TEST(Config, OverrideNumberBeyondRangeNamesTheKey) {
  auto error_of = [](const std::string& override_text) {
    try {
      parse_config("", "c.toml", {override_text});
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("task.eval_seconds=1e999"),
            "--set task.eval_seconds=1e999: task.eval_seconds = 1e999 is out of range (not "
            "representable as a 64-bit number); allowed: number in (0.0, 3600.0] s");
  EXPECT_EQ(error_of("run.seed=99999999999999999999"),
            "--set run.seed=99999999999999999999: run.seed = 99999999999999999999 is out of "
            "range (not representable as a 64-bit number); allowed: integer in [0, "
            "9000000000000000]");
  EXPECT_NE(error_of("task.eval_seconds=nan").find("task.eval_seconds = nan is out of range"),
            std::string::npos);
  // A bare word that starts with a digit is still a string.
  EXPECT_EQ(parse_config("", "c.toml", {"controller.crossover_method=1pointpl"})
                .controller.crossover_method,
            CrossoverMethod::one_point_per_layer);
}

TEST(Config, BrokenConfigsGiveTheirExactError) {
  const fs::path dir = source_dir() / "tests/data/bad_configs";
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    std::ifstream in(entry.path());
    std::string first_line;
    std::getline(in, first_line);
    const std::string marker = "# expect: ";
    ASSERT_EQ(first_line.rfind(marker, 0), 0u) << entry.path() << " lacks an expect line";
    const std::string expected = first_line.substr(marker.size());
    std::stringstream rest;
    rest << in.rdbuf();
    const std::string name = entry.path().filename().string();
    try {
      parse_config(first_line + "\n" + rest.str(), name);
      ADD_FAILURE() << name << " parsed without error";
    } catch (const ConfigError& e) {
      if (expected.find("TOML syntax error") != std::string::npos) {
        // The parser's own wording is toml++'s; pin file, line and our prefix.
        EXPECT_EQ(std::string(e.what()).rfind(name + ":3: TOML syntax error: ", 0), 0u) << e.what();
      } else {
        EXPECT_EQ(std::string(e.what()), expected) << name;
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

// run.stop_after_failed_generations: absent from the text at its default (every existing config
// hash stays), parsed, ranged.
TEST(Config, StopAfterFailedGenerationsEntersTheTextOnlyOffItsDefault) {
  EXPECT_EQ(Config{}.run.stop_after_failed_generations, 1);
  EXPECT_EQ(canonical_text(Config{}).find("stop_after_failed_generations"), std::string::npos);
  const Config c = parse_config("[run]\nstop_after_failed_generations = 0\n", "s.toml");
  EXPECT_EQ(c.run.stop_after_failed_generations, 0);
  EXPECT_NE(canonical_text(c).find("stop_after_failed_generations = 0"), std::string::npos);
  EXPECT_EQ(canonical_text(parse_config(canonical_text(c), "canonical")), canonical_text(c));
  expect_config_error("[run]\nstop_after_failed_generations = -1\n", "s.toml", "out of range");
}

// Hostile text meets a stated limit, not the stack: a 50,000-digit number and an inline table
// 10,000 deep each crashed every reader (issue 39). Brackets inside strings and comments do not
// nest, and a line at the limit still parses.
TEST(Config, LongLinesAndDeepNestingAreClearErrors) {
  const std::string digits(50000, '7');
  expect_config_error("[run]\nseed = " + digits + "\n", "long.toml",
                      "long.toml:2: this line is 50007 bytes; a config line may be at most 10000 "
                      "bytes");
  std::string deep = "x = ";  // an inline table 10,000 deep
  for (int i = 0; i < 10000; ++i) deep += "{a=";
  deep += "1";
  for (int i = 0; i < 10000; ++i) deep += "}";
  expect_config_error("[run]\n" + deep + "\n", "deep.toml",
                      "deep.toml:2: arrays and inline tables nested more than 8 deep");
  std::string deep_lines;
  for (int i = 0; i < 10000; ++i) deep_lines += "[\n";
  expect_config_error("[neat]\nactivation_options = " + deep_lines, "lines.toml",
                      "lines.toml:10: arrays and inline tables nested more than 8 deep");
  // The same limits for --set values.
  try {
    parse_config("", "c.toml", {"run.seed=" + digits});
    ADD_FAILURE() << "a 50,000-digit --set value parsed";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--set run.seed: the value is 50000 bytes; a config line may be at most 10000 "
              "bytes");
  }
  // Not nesting: brackets in strings (an unknown activation then) and in comments.
  try {
    parse_config("[neat]\nactivation_options = [\"[[[[[[[[[[{{{{\"] # [[[[[[[[[[[[\n", "s.toml");
    ADD_FAILURE() << "an unknown activation parsed";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).find("nested"), std::string::npos) << e.what();
  }
  // At the limit: a comment line of exactly kMaxConfigLineBytes bytes.
  EXPECT_NO_THROW(parse_config("# " + std::string(kMaxConfigLineBytes - 2, 'x') + "\n", "c.toml"));
}

// Keys that scale a run's cost are checked against the population (issue 39): at population 4,
// min_species_size = 1e9 grew memory by 300 MB/s and 100 evaluated 159 robots a generation; a
// tournament of 1e9 spent CPU in proportion. A timeout near 1e10 s overflowed the clock.
TEST(Config, SizesBeyondThePopulationAndHugeTimeoutsAreRefused) {
  expect_config_error("[neat]\npop_size = 4\nmin_species_size = 1000000000\n", "m.toml",
                      "m.toml: neat.min_species_size = 1000000000 must be <= neat.pop_size = 4");
  expect_config_error("[neat]\npop_size = 4\nmin_species_size = 100\n", "m.toml",
                      "neat.min_species_size = 100 must be <= neat.pop_size = 4");
  expect_config_error("[neat]\npop_size = 4\ntournament_size = 1000000000\n", "t.toml",
                      "t.toml: neat.tournament_size = 1000000000 must be <= neat.pop_size = 4");
  EXPECT_NO_THROW(
      parse_config("[neat]\npop_size = 4\nmin_species_size = 4\ntournament_size = 4\n", "ok.toml"));
  expect_config_error("[run]\neval_timeout_seconds = 1e10\n", "x.toml",
                      "run.eval_timeout_seconds = 1e+10 is out of range");
  EXPECT_EQ(parse_config("[run]\neval_timeout_seconds = 1e7\n", "x.toml").run.eval_timeout_seconds,
            1.0e7);
}

}  // namespace softevo
