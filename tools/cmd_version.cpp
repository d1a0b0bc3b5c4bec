#include <cstdio>

#include "common/version.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {

void register_version(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("version", "print the softevo version and git commit");
  cmd->callback([&exit_code] {
    std::printf("softevo %s (commit %s)\n", kVersion, kGitCommit);
    exit_code = kExitOk;
  });
}

}  // namespace softevo::cli
