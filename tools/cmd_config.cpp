#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/config_identity.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {
namespace {

// The resolved config as JSON: {"config_hash", "experiment_hash", "config": {section: {key:
// value}}}. A TOML value that is also JSON (numbers, arrays, booleans, basic strings) is kept
// as such; the rest (nan, inf) as its TOML text.
nlohmann::ordered_json config_json(const Config& config) {
  nlohmann::ordered_json sections = nlohmann::ordered_json::object();
  for (const auto& [key, value] : canonical_entries(canonical_text(config))) {
    const std::size_t dot = key.find('.');
    nlohmann::ordered_json v = nlohmann::ordered_json::parse(value, nullptr, false);
    sections[key.substr(0, dot)][key.substr(dot + 1)] =
        v.is_discarded() ? nlohmann::ordered_json(value) : v;
  }
  nlohmann::ordered_json j;
  j["config_hash"] = hash_hex(config_hash(config));
  j["experiment_hash"] = hash_hex(experiment_hash(config));
  j["config"] = std::move(sections);
  return j;
}

}  // namespace

void register_config(CLI::App& app, int& exit_code) {
  auto* config_cmd = app.add_subcommand("config", "inspect configuration files");
  config_cmd->require_subcommand(1);
  auto* show = config_cmd->add_subcommand(
      "show", "print the fully resolved config (every key, canonical form) and its hash");
  auto file = std::make_shared<std::string>();
  auto overrides = std::make_shared<std::vector<std::string>>();
  auto hash_only = std::make_shared<bool>(false);
  auto json = std::make_shared<bool>(false);
  show->add_option("FILE", *file, "TOML config file")->required();
  show->add_option("--set", *overrides, "override a key: section.key=value (repeatable)");
  auto* hash_flag = show->add_flag("--hash", *hash_only, "print only the 64-bit config hash");
  show->add_flag("--json", *json, "print one JSON object (hashes and every key by section)")
      ->excludes(hash_flag);
  show->callback([&exit_code, file, overrides, hash_only, json] {
    const Config config = load_config(*file, *overrides);
    if (*json) {
      std::printf("%s\n", config_json(config).dump(2).c_str());
    } else if (*hash_only) {
      std::printf("%s\n", hash_hex(config_hash(config)).c_str());
    } else {
      std::printf("# config_hash = \"%s\"\n%s", hash_hex(config_hash(config)).c_str(),
                  canonical_text(config).c_str());
    }
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
