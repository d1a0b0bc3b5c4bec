// `softevo`: single-process command line for everything that is not the distributed run.
// Every error is printed as "softevo: error: <what>" (exit 2); --version and `softevo version`
// print the version.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "common/closest_word.hpp"
#include "tools/commands.hpp"
#include "tools/run_command.hpp"

namespace softevo::cli {

bool is_subcommand(const CLI::App& app, const std::string& word) {
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    if (sub->check_name(word)) return true;
  return false;
}

std::string closest_subcommand(const CLI::App& app, const std::string& word) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(sub->get_name());
  return closest_word(word, names);
}

}  // namespace softevo::cli

int main(int argc, char** argv) {
  CLI::App app{"softevo: co-evolution of pneumatic soft robot bodies and brains (single process)"};
  app.require_subcommand(1);
  app.footer(
      "Start with `softevo evolve` (an evolution on this machine's cores). On a cluster the same "
      "options, archive and results come from the MPI program softevo-mpi, built next to this "
      "one: `mpirun -np N softevo-mpi --config FILE ...` (softevo-mpi --help; docs/mpi-local.md, "
      "docs/archive.md).");
  int exit_code = softevo::cli::kExitOk;
  softevo::cli::register_evolve(app, exit_code);
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
  softevo::cli::register_fabricate(app, exit_code);
  softevo::cli::register_repair(app, exit_code);
#ifdef SOFTEVO_HAVE_VIEW
  softevo::cli::register_view(app, exit_code);
#endif
  // A first word that is no option and no command is a mistyped command: CLI11 would only say
  // that a subcommand is required.
  if (argc > 1 && argv[1][0] != '-' && !softevo::cli::is_subcommand(app, argv[1])) {
    const std::string guess = softevo::cli::closest_subcommand(app, argv[1]);
    std::fprintf(stderr, "softevo: error: unknown command '%s'%s (softevo --help lists them)\n",
                 argv[1], guess.empty() ? "" : (", did you mean " + guess + "?").c_str());
    return softevo::cli::kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One prefix for every error: CLI11's own messages get it too.
    std::fprintf(stderr, "softevo: error: %s\n", e.what());
    const std::string hints = softevo::option_suggestions(app);
    if (!hints.empty()) std::fprintf(stderr, "%s", hints.c_str());
    const CLI::App* failing = &app;
    for (const CLI::App* sub : app.get_subcommands())
      if (sub->parsed()) failing = sub;
    std::fprintf(stderr, "run with --help for more information (softevo %s--help)\n",
                 failing == &app ? "" : (failing->get_name() + " ").c_str());
    return softevo::cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softevo: error: %s\n", e.what());
    return softevo::cli::kExitUsage;
  }
  return exit_code;
}
