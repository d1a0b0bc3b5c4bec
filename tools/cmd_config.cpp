#include <cstdio>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {

void register_config(CLI::App& app, int& exit_code) {
  auto* config_cmd = app.add_subcommand("config", "inspect configuration files");
  config_cmd->require_subcommand(1);
  auto* show = config_cmd->add_subcommand(
      "show", "print the fully resolved config (every key, canonical form) and its hash");
  auto file = std::make_shared<std::string>();
  auto overrides = std::make_shared<std::vector<std::string>>();
  auto hash_only = std::make_shared<bool>(false);
  show->add_option("FILE", *file, "TOML config file")->required();
  show->add_option("--set", *overrides, "override a key: section.key=value (repeatable)");
  show->add_flag("--hash", *hash_only, "print only the 64-bit config hash");
  show->callback([&exit_code, file, overrides, hash_only] {
    const Config config = load_config(*file, *overrides);
    if (*hash_only) {
      std::printf("%s\n", hash_hex(config_hash(config)).c_str());
    } else {
      std::printf("# config_hash = \"%s\"\n%s", hash_hex(config_hash(config)).c_str(),
                  canonical_text(config).c_str());
    }
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
