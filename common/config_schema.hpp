// The config schema, internal to common/config*.cpp: one row per key (its section, name,
// target member, range or allowed names, unit conversion and when it applies). Parsing,
// validation, printing and hashing (common/config.cpp) all walk these rows, so a key cannot be
// parsed but not printed or hashed.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "common/config.hpp"

namespace softevo::config_schema {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kPascalPerBar = 1.0e5;

using Target =
    std::variant<double*, std::int64_t*, bool*, std::string*, TaskKind*, std::vector<double>*,
                 std::vector<std::int64_t>*, std::vector<std::string>*, FailurePolicy*,
                 ControlLoop*, Integrator*, GroundKind*, HeightfieldKind*, TerrainResample*,
                 SupplyScaling*, CrossoverMethod*, ControllerInit*, DistanceInput*, LearningMethod*,
                 Inheritance*, SearchKind*, AfpoAge*>;

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

// The sections of a config file, in the order of the canonical text.
extern const std::vector<std::string> kSections;

// The rows of every key, each bound to its member of `c`.
std::vector<KeyDef> schema(Config& c);

// The strings a string, choice or string-list key accepts (empty: any string).
std::vector<std::string> allowed_strings(const KeyDef& def);

// When keys apply (a key printed and settable only under a condition; validation reads them too).
bool terrain_not_flat(const Config& c);
bool terrain_heightfield(const Config& c);
bool terrain_bumps(const Config& c);
bool terrain_steps(const Config& c);
bool learning_on(const Config& c);
bool supply_scaled(const Config& c);
bool search_map_elites(const Config& c);
bool search_afpo(const Config& c);

}  // namespace softevo::config_schema
