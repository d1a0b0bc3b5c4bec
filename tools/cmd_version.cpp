#include <cstdio>
#include <string>

#include "common/version.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {

std::string version_line() {
  return std::string("softevo ") + kVersion + " (commit " + git_commit() + ")";
}

void register_version(CLI::App& app, int& exit_code) {
  app.set_version_flag("--version", version_line());
  auto* cmd = app.add_subcommand("version", "print the softevo version and git commit");
  cmd->callback([&exit_code] {
    std::printf("%s\n", version_line().c_str());
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
