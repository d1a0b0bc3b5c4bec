// `softevo`: single-process command line for everything that is not the distributed run.
#include <cstdio>
#include <exception>

#include "tools/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"softevo: co-evolution of pneumatic soft robot bodies and brains (single process)"};
  app.require_subcommand(1);
  int exit_code = softevo::cli::kExitOk;
  softevo::cli::register_version(app, exit_code);
  softevo::cli::register_config(app, exit_code);
  softevo::cli::register_bench_physics(app, exit_code);
  softevo::cli::register_bench_xor(app, exit_code);
  softevo::cli::register_develop(app, exit_code);
  softevo::cli::register_render(app, exit_code);
  softevo::cli::register_replay(app, exit_code);
  softevo::cli::register_eval(app, exit_code);
  softevo::cli::register_champions(app, exit_code);
  softevo::cli::register_bench_eval(app, exit_code);
  softevo::cli::register_info(app, exit_code);
  softevo::cli::register_export(app, exit_code);
  softevo::cli::register_repair(app, exit_code);
#ifdef SOFTEVO_HAVE_VIEW
  softevo::cli::register_view(app, exit_code);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : softevo::cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softevo: error: %s\n", e.what());
    return softevo::cli::kExitUsage;
  }
  return exit_code;
}
