#include "tools/run_command.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "common/closest_word.hpp"
#include "common/config.hpp"
#include "common/launcher_watch.hpp"
#include "io/archive.hpp"
#include "master/signals.hpp"
#include "tools/cli_checks.hpp"

#ifndef SOFTEVO_DEFAULT_SOURCE_DIR
#define SOFTEVO_DEFAULT_SOURCE_DIR "."
#endif

namespace softevo {
namespace {

namespace fs = std::filesystem;

std::string resolve_config_path(const std::string& path) {
  if (path != kDefaultRunConfig || fs::exists(path)) return path;
  const std::string baked = std::string(SOFTEVO_DEFAULT_SOURCE_DIR) + "/" + kDefaultRunConfig;
  return fs::exists(baked) ? baked : path;
}

// The one archive naming scheme (configs' comments, slurm/grid.sbatch, the README):
// runs/<config name>-<seed, at least 2 digits>.h5.
std::string default_out_path(const std::string& config_path, std::int64_t seed) {
  char seed_text[32];
  std::snprintf(seed_text, sizeof seed_text, "%02lld", static_cast<long long>(seed));
  return "runs/" + fs::path(config_path).stem().string() + "-" + seed_text + ".h5";
}

// The overrides and shorthands of one run (and `seed` if >= 0).
std::vector<std::string> run_overrides(const RunCommandOptions& o, std::int64_t seed) {
  std::vector<std::string> overrides = o.overrides;
  if (o.seed >= 0) overrides.push_back("run.seed=" + std::to_string(o.seed));
  if (seed >= 0) overrides.push_back("run.seed=" + std::to_string(seed));
  if (o.generations >= 0) overrides.push_back("run.generations=" + std::to_string(o.generations));
  if (o.population >= 0) overrides.push_back("neat.pop_size=" + std::to_string(o.population));
  return overrides;
}

// The config of one run: `path` with the overrides and shorthands (and `seed` if >= 0).
Config run_config(const RunCommandOptions& o, const std::string& path, std::int64_t seed) {
  return load_config(path, run_overrides(o, seed));
}

// --resume of an existing archive without --config: the config the archive was written with
// (its /config), with only the overrides given now, so a resume needs no repeated --set.
std::optional<Config> archived_config(const RunCommandOptions& o) {
  std::error_code ec;
  if (!o.resume || !o.config_paths.empty() || !o.seeds.empty() || o.out_path.empty() ||
      !fs::exists(o.out_path, ec))
    return std::nullopt;
  std::string text;
  try {
    text = io::Archive(o.out_path).config_text();
  } catch (const std::exception& e) {
    throw master::StartupError(o.out_path + ": cannot resume: cannot read its config: " + e.what());
  }
  // An override of the strategy would otherwise fail on the first key of the archive's own
  // strategy ("map_elites.descriptors applies only when ..."), not saying why.
  const std::string archived = master::archived_strategy(text);
  for (const std::string& override : o.overrides) {
    if (override.rfind("search.strategy=", 0) != 0) continue;
    std::string wanted = override.substr(std::string("search.strategy=").size());
    const auto quote_or_space = [](char c) { return c == '"' || c == '\'' || c == ' '; };
    while (!wanted.empty() && quote_or_space(wanted.back())) wanted.pop_back();
    wanted.erase(0, std::min(wanted.size(), wanted.find_first_not_of("\"' ")));
    if (wanted != archived) master::refuse_other_strategy(o.out_path, archived, wanted, {});
  }
  return parse_config(text, o.out_path + " (its /config)", run_overrides(o, -1));
}

master::RunOptions run_options(const RunCommandOptions& o, std::string out_path) {
  master::RunOptions ro;
  ro.out_path = std::move(out_path);
  ro.program = o.program;
  // The archive's folder is created, whether the default runs/ or the one --out names (the
  // output checks then say why, should that fail).
  const fs::path parent = fs::path(ro.out_path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
  }
  ro.resume = o.resume;
  ro.overwrite = o.overwrite;
  ro.reuse_results = !o.no_reuse;
  ro.longest_first = !o.fixed_order;
  return ro;
}

}  // namespace

std::string option_suggestions(const CLI::App& app) {
  // The options of the command that failed: the innermost parsed subcommand.
  const CLI::App* failing = &app;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (const CLI::App* sub : failing->get_subcommands())
      if (sub->parsed()) {
        failing = sub;
        deeper = true;
        break;
      }
  }
  std::vector<std::string> names;
  for (const CLI::Option* opt : failing->get_options()) {
    for (const std::string& l : opt->get_lnames()) names.push_back("--" + l);
  }
  std::string out;
  for (const std::string& arg : app.remaining(true)) {
    if (!arg.starts_with("--")) continue;
    const std::string word = arg.substr(0, arg.find('='));
    const std::string guess = closest_word(word, names);
    if (!guess.empty()) out += "unknown option " + word + ", did you mean " + guess + "?\n";
  }
  return out;
}

void add_run_options(CLI::App& app, RunCommandOptions& o) {
  using cli::at_least;
  app.add_option("--config", o.config_paths,
                 "TOML config file (default configs/quickstart.toml); repeatable with --seeds");
  // The -1 defaults mean "the config's" (tools/cli_checks.hpp).
  app.add_option("--seed", o.seed, "run seed (sets run.seed)")->check(at_least(0));
  app.add_option("-o,--output,--out", o.out_path,
                 "run archive (default runs/<config>-<seed, 2 digits>.h5; its folder is created)");
  app.add_option("--seeds", o.seeds,
                 "several runs in one job sharing the workers, one per config and seed "
                 "(e.g. 1-10 or 1,3,5-7)");
  app.add_option("--out-dir", o.out_dir,
                 "archives of --seeds: DIR/<config name>-<seed, 2 digits>.h5 (default runs)");
  app.add_option("--generations", o.generations, "generations to evaluate (run.generations)")
      ->check(at_least(1));
  app.add_option("--population", o.population, "population size (neat.pop_size)")
      ->check(at_least(1));
  app.add_option("--set", o.overrides, "override a key: section.key=value (repeatable)");
  app.add_flag("--resume", o.resume,
               "continue the archive from its newest checkpoint (with --config: a new run if it "
               "does not exist; without: the archive must exist)");
  app.add_flag("--overwrite", o.overwrite, "replace an existing archive");
  app.add_option("--progress", o.progress,
                 "the live line within a generation: auto (a terminal, or an interactive "
                 "mpirun/srun), always or never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
  auto* quiet = app.add_flag("-q,--quiet", o.quiet, "warnings and errors only");
  app.add_flag("-v,--verbose", o.verbose, "print the resolved config at the start too")
      ->excludes(quiet);
  app.add_flag("--no-reuse", o.no_reuse,
               "simulate every genome, also one evaluated before (for measuring; same results)");
  app.add_flag("--fixed-order", o.fixed_order,
               "hand out units in member order, not longest first (for measuring; same results)");
}

std::vector<std::int64_t> parse_seeds(const std::string& spec) {
  const auto bad = [&spec](const std::string& why) {
    return ConfigError("--seeds " + spec + ": " + why +
                       " (give seeds and ranges, e.g. 1-10 or 1,3,5-7)");
  };
  const auto number = [&](const std::string& text) {
    std::size_t used = 0;
    long long v = -1;
    try {
      v = std::stoll(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || text.empty() || v < 0) throw bad("'" + text + "' is not a seed");
    return static_cast<std::int64_t>(v);
  };
  std::vector<std::int64_t> seeds;
  std::size_t start = 0;
  while (start <= spec.size()) {
    const std::size_t comma = std::min(spec.find(',', start), spec.size());
    const std::string item = spec.substr(start, comma - start);
    const std::size_t dash = item.find('-');
    const std::int64_t first = number(item.substr(0, dash));
    const std::int64_t last = dash == std::string::npos ? first : number(item.substr(dash + 1));
    if (last < first) throw bad("the range " + item + " is empty");
    if (last - first >= 10000) throw bad("the range " + item + " has more than 10000 seeds");
    for (std::int64_t v = first; v <= last; ++v) {
      if (std::find(seeds.begin(), seeds.end(), v) != seeds.end())
        throw bad("seed " + std::to_string(v) + " is given twice");
      seeds.push_back(v);
    }
    start = comma + 1;
  }
  return seeds;
}

namespace {

// The memory estimate of a job before any run is prepared (issue 29: a population of 10^6
// filled gigabytes before generation 0): refused beyond the machine's memory, warned near it.
void check_job_memory(const std::vector<const Config*>& configs) {
  const std::string warning = master::check_run_memory(configs, available_memory());
  if (!warning.empty()) std::fprintf(stderr, "warning: %s\n", warning.c_str());
}

// --resume without --config continues an archive, which must exist: a mistyped --out (or none)
// silently started a run of the default config (issue 39). With --config, --resume still starts
// the run when its archive is absent (the Slurm scripts pass it on every start and requeue).
void check_resume_has_an_archive(const RunCommandOptions& o) {
  if (!o.resume || !o.config_paths.empty() || !o.seeds.empty()) return;
  if (o.out_path.empty())
    throw master::StartupError(
        "--resume without --config continues the archive that --out names: give --out (or "
        "--config, to start or continue that config's run); nothing was started");
  std::error_code ec;
  if (fs::exists(o.out_path, ec)) return;
  fs::path dir = fs::path(o.out_path).parent_path();
  if (dir.empty()) dir = ".";
  const std::string wanted = fs::path(o.out_path).filename().string();
  std::vector<std::pair<std::size_t, std::string>> near;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator();
       it.increment(ec)) {
    if (it->path().extension() != ".h5") continue;
    const std::string name = it->path().filename().string();
    near.emplace_back(edit_distance(wanted, name), (dir / name).string());
  }
  std::sort(near.begin(), near.end());
  std::string listing;
  for (std::size_t i = 0; i < near.size() && i < 5; ++i)
    listing += (i == 0 ? "" : ", ") + near[i].second;
  throw master::StartupError(
      o.out_path + ": cannot resume: no such archive; " +
      (listing.empty()
           ? "no archive (*.h5) in " + dir.string()
           : "archives near it: " + listing +
                 (near.size() > 5 ? " (" + std::to_string(near.size()) + " in all)" : "")) +
      "; give --config to start a new run; nothing was started");
}

}  // namespace

std::vector<master::PreparedRun> prepare_runs(RunCommandOptions& o, int ranks) {
  check_resume_has_an_archive(o);
  if (const std::optional<Config> config = archived_config(o)) {
    o.from_archive = true;
    check_job_memory({&*config});
    std::vector<master::PreparedRun> runs;
    runs.push_back(master::prepare_run(*config, run_options(o, o.out_path), ranks));
    return runs;
  }
  if (o.config_paths.empty()) o.config_paths.push_back(kDefaultRunConfig);
  for (std::string& path : o.config_paths) path = resolve_config_path(path);
  std::vector<master::PreparedRun> runs;
  if (o.seeds.empty()) {
    if (o.config_paths.size() > 1)
      throw ConfigError("--config is given " + std::to_string(o.config_paths.size()) +
                        " times: several configs run in one job only with --seeds");
    if (!o.out_dir.empty())
      throw ConfigError("--out-dir names the archives of --seeds; one run takes --out");
    const Config config = run_config(o, o.config_paths.front(), -1);
    check_job_memory({&config});
    const std::string out =
        o.out_path.empty() ? default_out_path(o.config_paths.front(), config.run.seed) : o.out_path;
    runs.push_back(master::prepare_run(config, run_options(o, out), ranks));
    return runs;
  }
  if (!o.out_path.empty())
    throw ConfigError(
        "--out names one archive; with --seeds give --out-dir (each run writes "
        "<out-dir>/<config name>-<seed>.h5)");
  if (o.seed >= 0) throw ConfigError("--seed and --seeds contradict each other; give one of them");
  const std::vector<std::int64_t> seeds = parse_seeds(o.seeds);
  {
    // One config per file (a run's memory does not depend on its seed).
    std::vector<Config> configs;
    for (const std::string& path : o.config_paths) configs.push_back(run_config(o, path, -1));
    std::vector<const Config*> job;
    for (const Config& c : configs)
      for (std::size_t i = 0; i < seeds.size(); ++i) job.push_back(&c);
    check_job_memory(job);
  }
  // Every run holds its lock's descriptor for the whole job: check before the first is taken
  // (issue 29: 1,100 seeds under ulimit -n 1024 failed midway, misleadingly, leaving locks).
  master::reserve_descriptors(seeds.size() * o.config_paths.size());
  const std::string dir = o.out_dir.empty() ? "runs" : o.out_dir;
  std::error_code ec;
  const bool dir_existed = fs::exists(dir, ec);
  fs::create_directories(dir, ec);
  try {
    std::vector<std::string> outs;
    for (const std::string& path : o.config_paths) {
      for (const std::int64_t seed : seeds) {
        char name[64];
        std::snprintf(name, sizeof name, "-%02lld.h5", static_cast<long long>(seed));
        const std::string out = (fs::path(dir) / (fs::path(path).stem().string() + name)).string();
        if (std::find(outs.begin(), outs.end(), out) != outs.end())
          throw ConfigError(out +
                            ": two runs of this job would write it (two --config files of "
                            "the same name)");
        outs.push_back(out);
        runs.push_back(master::prepare_run(run_config(o, path, seed), run_options(o, out), ranks));
      }
    }
  } catch (...) {
    // A job that does not start leaves nothing behind: the lock files its runs created, and
    // the folder it created (fs::remove removes only an empty one).
    for (master::PreparedRun& run : runs)
      if (run.lock) run.lock->abandon();
    if (!dir_existed) fs::remove(dir, ec);
    throw;
  }
  return runs;
}

std::string config_paths_text(const RunCommandOptions& o) {
  if (o.from_archive) return o.out_path + " (the archive's config)";
  std::string text;
  for (const std::string& p : o.config_paths) text += (text.empty() ? "" : ", ") + p;
  return text;
}

EvalResult evaluate_unit(const std::vector<master::PreparedRun>& runs,
                         const std::vector<std::unique_ptr<tasks::Task>>& tasks,
                         const EvalRequest& request, const worker::EvaluateOptions& options) {
  std::size_t i = 0;
  for (std::size_t r = 0; r < runs.size(); ++r)
    if (runs[r].config_hash == request.config_hash) i = r;
  return worker::evaluate(runs[i].config, *tasks[i], runs[i].config_hash, request, options);
}

worker::EvaluateOptions abandoning_on_stop(worker::EvaluateOptions options) {
  options.abandon = [earlier = options.abandon] {
    if (launcher_gone()) master::request_stop(master::StopRequest::now);
    return (earlier && earlier()) || master::stop_requested() == master::StopRequest::now;
  };
  return options;
}

}  // namespace softevo
