// Strict TOML config: parsing, validation, overrides and the canonical text, each walking the
// schema's rows (common/config_schema.hpp), so a key cannot be parsed but not printed (or
// hashed). The hashes of the canonical text are in common/config_identity.cpp.
#include "common/config.hpp"
#include "common/closest_word.hpp"
#include "common/config_identity.hpp"
#include "common/config_schema.hpp"
#include "common/input_file.hpp"
#include "common/map_grid.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>
#include <variant>

#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

namespace softevo {
namespace {

using config_schema::allowed_strings;
using config_schema::KeyDef;
using config_schema::kInf;
using config_schema::kPascalPerBar;
using config_schema::kSections;
using config_schema::learning_on;
using config_schema::schema;
using config_schema::supply_scaled;
using config_schema::terrain_bumps;
using config_schema::terrain_not_flat;
using config_schema::terrain_steps;

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
  // Unbounded: a number must still be finite (nan and inf are refused).
  return std::string(integer ? "integer" : "finite number") + unit;
}

std::string allowed_text(const KeyDef& def) {
  return std::visit(
      [&](auto* target) -> std::string {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, double>) return range_text(def, false);
        if constexpr (std::is_same_v<T, std::int64_t>) return range_text(def, true);
        if constexpr (std::is_same_v<T, bool>) return "true or false";
        if constexpr (std::is_same_v<T, std::string> || ConfigChoice<T>) {
          std::vector<std::string> q;
          for (const auto& a : allowed_strings(def)) q.push_back(quote(a));
          return "one of " + join(q);
        }
        if constexpr (std::is_same_v<T, std::vector<double>>) {
          const std::string each = range_text(def, false);
          return std::string(def.list_length ? "array of " + std::to_string(def.list_length)
                                             : "non-empty array of") +
                 (each == "finite number" ? " finite numbers" : " numbers, each " + each);
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
  // A species is kept at max(min_species_size, elitism) members or more (docs/model.md §8.5), so
  // either above the population makes every generation larger than it (a population of 4 with
  // min_species_size = 100 evaluated 159 robots); a tournament larger than the population
  // draws the same members again at a cost in proportion to its size (issue 39).
  // (elitism has its own check below.)
  for (const auto& [key, value] : {std::pair{"min_species_size", c.neat.min_species_size},
                                   std::pair{"tournament_size", c.neat.tournament_size}}) {
    if (value > c.neat.pop_size)
      fail(at, "neat." + std::string(key) + " = " + std::to_string(value) +
                   " must be <= neat.pop_size = " + std::to_string(c.neat.pop_size));
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

// The limits of config.hpp (kMaxConfigLineBytes, kMaxConfigNesting) over `text`, in one pass
// that follows TOML's strings and comments (a bracket inside "..." or after # does not nest).
// Iterative on purpose: the text may be hostile.
void check_text_shape(const std::string& text, const Location& where) {
  enum class In { code, comment, basic, literal, multiline_basic, multiline_literal };
  In in = In::code;
  int depth = 0;
  std::int64_t line = where.line;  // 0: a --set value, whose message names no line
  std::size_t line_start = 0;
  const auto here = [&] { return Location{where.source, line}; };
  const auto at = [&](std::size_t i, const char* three) { return text.compare(i, 3, three) == 0; };
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == '\n') {
      if (i - line_start > kMaxConfigLineBytes)
        fail(here(), std::string(line > 0 ? "this line is " : "the value is ") +
                         std::to_string(i - line_start) + " bytes; a config line may be at most " +
                         std::to_string(kMaxConfigLineBytes) + " bytes");
      if (in != In::multiline_basic && in != In::multiline_literal) in = In::code;
      if (line > 0) ++line;
      line_start = i + 1;
      continue;
    }
    const char c = text[i];
    switch (in) {
      case In::code:
        if (c == '#') {
          in = In::comment;
        } else if (at(i, "\"\"\"")) {
          in = In::multiline_basic;
          i += 2;
        } else if (at(i, "'''")) {
          in = In::multiline_literal;
          i += 2;
        } else if (c == '"') {
          in = In::basic;
        } else if (c == '\'') {
          in = In::literal;
        } else if (c == '[' || c == '{') {
          if (++depth > kMaxConfigNesting)
            fail(here(), "arrays and inline tables nested more than " +
                             std::to_string(kMaxConfigNesting) +
                             " deep; a config nests them at most that deep");
        } else if ((c == ']' || c == '}') && depth > 0) {
          --depth;
        }
        break;
      case In::basic:
      case In::multiline_basic:
        if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n') {
          ++i;  // an escaped character, a quote among them
        } else if (in == In::basic && c == '"') {
          in = In::code;
        } else if (in == In::multiline_basic && at(i, "\"\"\"")) {
          in = In::code;
          i += 2;
        }
        break;
      case In::literal:
        if (c == '\'') in = In::code;
        break;
      case In::multiline_literal:
        if (at(i, "'''")) {
          in = In::code;
          i += 2;
        }
        break;
      case In::comment:
        break;
    }
  }
}

void apply_override(Config& config, const std::string& text, SetKeys& set_keys,
                    OverrideOrigin origin) {
  const auto eq_at = text.find('=');
  const Location at{origin == OverrideOrigin::command_line
                        ? "--set " + text
                        : "overrides[\"" + text.substr(0, eq_at) + "\"]" +
                              (eq_at == std::string::npos ? "" : " = " + text.substr(eq_at + 1)),
                    0};
  const auto eq = text.find('=');
  const auto dot = text.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
    fail(at, "expected section.key=value");
  }
  const std::string section = text.substr(0, dot);
  const std::string key = text.substr(dot + 1, eq - dot - 1);
  const std::string value = text.substr(eq + 1);
  check_text_shape(
      value, {origin == OverrideOrigin::command_line ? "--set " + text.substr(0, eq)
                                                     : "overrides[\"" + text.substr(0, eq) + "\"]",
              0});
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

bool is_key_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-';
}
bool is_blank(char c) {
  return c == ' ' || c == '\t';
}

// A bare key at `i` of `line` (after blanks), or empty; `i` moves past it and the blanks after.
std::string_view scan_key(std::string_view line, std::size_t& i) {
  while (i < line.size() && is_blank(line[i])) ++i;
  const std::size_t start = i;
  while (i < line.size() && is_key_char(line[i])) ++i;
  const std::string_view key = line.substr(start, i - start);
  while (i < line.size() && is_blank(line[i])) ++i;
  return key;
}

// `[section]` (blanks allowed, a comment after it) gives the section's name, else empty.
std::string_view table_header(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && is_blank(line[i])) ++i;
  if (i == line.size() || line[i] != '[') return {};
  ++i;
  const std::string_view name = scan_key(line, i);
  if (name.empty() || i == line.size() || line[i] != ']') return {};
  ++i;
  while (i < line.size() && is_blank(line[i])) ++i;
  return i == line.size() || line[i] == '#' ? name : std::string_view{};
}

// `key = value` gives the key and the value's first word (up to a blank, #, comma or ]).
std::optional<std::pair<std::string_view, std::string_view>> key_and_value(std::string_view line) {
  std::size_t i = 0;
  const std::string_view key = scan_key(line, i);
  if (key.empty() || i == line.size() || line[i] != '=') return std::nullopt;
  ++i;
  while (i < line.size() && is_blank(line[i])) ++i;
  const std::size_t start = i;
  while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i])) && line[i] != '#' &&
         line[i] != ',' && line[i] != ']')
    ++i;
  if (i == start) return std::nullopt;
  return std::make_pair(key, line.substr(start, i - start));
}

// A TOML syntax error on `at.line` that is a number out of range ("eval_seconds = 1e999" under
// [task]) is reported as such, naming the key; any other syntax error is left to the caller.
void fail_if_unrepresentable_on_line(Config& config, const std::string& toml_text,
                                     const Location& at) {
  std::istringstream lines(toml_text);
  std::string text, section;
  for (std::int64_t number = 1; std::getline(lines, text) && number <= at.line; ++number) {
    const std::string_view header = table_header(text);
    if (!header.empty()) section = header;
    if (number < at.line) continue;
    const auto assignment = key_and_value(text);
    if (!assignment) continue;
    const auto defs = schema(config);
    const KeyDef* def = find_def(defs, section, std::string(assignment->first));
    const std::string value(assignment->second);
    if (def && is_unrepresentable_number(value)) fail_unrepresentable(*def, at, value);
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
                    const std::vector<std::string>& overrides, OverrideOrigin origin) {
  Config config;
  check_text_shape(toml_text, {source_name, 1});
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
  for (const auto& o : overrides) apply_override(config, o, set_keys, origin);
  check_task_keys(config, set_keys);
  check_consistency(config, source_name);
  // The MAP-Elites grid's relations between keys (common/map_grid.hpp).
  if (config_schema::search_map_elites(config)) map_grid(config, source_name);
  return config;
}

Config load_config(const std::string& path, const std::vector<std::string>& overrides,
                   OverrideOrigin origin) {
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
  // A file of another kind is named as such, not reported as a TOML syntax error (issue 39:
  // `evolve --config robot.json` said "TOML syntax error" on line 1).
  const FileMagic magic = file_magic(path);
  switch (magic) {
    case FileMagic::json:
      throw ConfigError(path +
                        ": is a JSON file (a robot file?), not a TOML config; robot files go to "
                        "softevo eval, render and view, and carry their run's config");
    case FileMagic::hdf5:
      throw ConfigError(path +
                        ": is an HDF5 file (a run archive?), not a TOML config; `softevo info` "
                        "shows an archive's config, and --resume --out continues its run");
    case FileMagic::png:
    case FileMagic::zip:
    case FileMagic::gzip:
      throw ConfigError(path + ": is a binary file (" +
                        (magic == FileMagic::png ? "PNG" : "compressed") + "), not a TOML config");
    case FileMagic::unknown:
      break;
  }
  return parse_config(text, path, overrides, origin);
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

std::string experiment_name(const Config& config) {
  // Controller learning is another experiment (docs/model.md §8.11): "gait-closed-learn"; so is
  // another search strategy (§8.12): "gait-open-map-elites", "gait-open-afpo".
  std::string learn = learning_on(config) ? "-learn" : "";
  if (config.search.strategy == SearchKind::map_elites) learn += "-map-elites";
  if (config.search.strategy == SearchKind::afpo) learn += "-afpo";
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
