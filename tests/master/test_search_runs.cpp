// Runs of the search strategies other than NEAT through the real loop (master/run.hpp) with the
// stand-in evaluator: the archive's strategy group, resume = the uninterrupted run, another
// strategy refused on resume, and a run whose every robot fails ends with an error.
#include <gtest/gtest.h>

#include <string>

#include "io/archive.hpp"
#include "master/run.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"

namespace softevo::master {
namespace {

Config strategy_config(SearchKind kind) {
  Config c = small_config();
  c.search.strategy = kind;
  c.map_elites.descriptors = {"voxels", "height"};
  c.map_elites.min = {0, 0};
  c.map_elites.max = {125, 0.05};
  c.map_elites.bins = {5, 5};
  return apply_overrides(c, {});  // checked like a config file
}

TEST(SearchRuns, ResumeOfAStrategyRunEqualsTheUninterruptedRun) {
  for (SearchKind kind : {SearchKind::map_elites, SearchKind::afpo}) {
    SCOPED_TRACE(to_string(kind));
    const test::TmpDir dir(true);
    Config c = strategy_config(kind);
    run_once(c, dir.file("whole.h5"), false);
    Config half = c;
    half.run.generations = 2;
    run_once(half, dir.file("parts.h5"), false);
    run_once(c, dir.file("parts.h5"), true);
    const io::Archive whole(dir.file("whole.h5"));
    const io::Archive parts(dir.file("parts.h5"));
    EXPECT_EQ(io::fitness_digest(parts), io::fitness_digest(whole));
    EXPECT_EQ(io::content_digest(parts), io::content_digest(whole));
    // Every generation carries the strategy's group: rows, metrics and (MAP-Elites) the map.
    for (std::int64_t g = 0; g < c.run.generations; ++g) {
      const io::GenerationRecord r = whole.generation(g);
      EXPECT_EQ(r.strategy.strategy, to_string(kind));
      EXPECT_EQ(r.strategy.rows.rows(), r.size());
      EXPECT_EQ(r.strategy.map.rows() > 0, kind == SearchKind::map_elites);
      EXPECT_GT(r.strategy.metric("max_fitness", -1.0), 0.0);
    }
  }
}

TEST(SearchRuns, ResumeWithAnotherStrategyIsRefusedNamingBoth) {
  const test::TmpDir dir(true);
  Config c = strategy_config(SearchKind::map_elites);
  c.run.generations = 1;
  run_once(c, dir.file("run.h5"), false);
  Config other = strategy_config(SearchKind::afpo);
  other.run.generations = 2;
  try {
    run_once(other, dir.file("run.h5"), true);
    FAIL() << "resumed with another strategy";
  } catch (const StartupError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("search strategy \"map_elites\", this run asks for \"afpo\""),
              std::string::npos)
        << what;
  }
  Config neat = small_config();
  neat.run.generations = 2;
  EXPECT_THROW(run_once(neat, dir.file("run.h5"), true), StartupError);
}

TEST(SearchRuns, ARunWhoseEveryRobotFailsEndsWithAnError) {
  const test::TmpDir dir(true);
  Config c = strategy_config(SearchKind::map_elites);
  c.run.stop_after_failed_generations = 0;  // the strategy itself must say so
  RunOptions options;
  options.out_path = dir.file("failed.h5");
  PreparedRun run = prepare_run(c, options, 1);
  LocalExecutor executor([](const EvalRequest& request) {
    EvalResult r = fake_evaluation(request);
    r.status = EvalStatus::failed;
    r.fitness = 0.0;
    return r;
  });
  ProgressReporter progress = ProgressReporter::silent();
  try {
    execute_run(run, executor, progress);
    FAIL() << "a run of failed robots completed";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("the map is empty"), std::string::npos) << e.what();
  }
}

TEST(SearchRuns, MemoryEstimateCountsTheMapAndAfposDoublePopulation) {
  Config neat = small_config();
  neat.neat.pop_size = 100;
  neat.run.generations = 1000;
  Config map = neat;
  map.search.strategy = SearchKind::map_elites;
  map.map_elites.max_cells = 400;  // fewer cells than robots: the map holds at most 400
  Config afpo = neat;
  afpo.search.strategy = SearchKind::afpo;
  EXPECT_EQ(estimate_run_memory(map) - estimate_run_memory(neat), 400 * kBytesPerMember);
  EXPECT_EQ(estimate_run_memory(afpo) - estimate_run_memory(neat), 100 * kBytesPerMember);
  map.run.generations = 2;  // fewer robots than cells: at most 200 elites
  EXPECT_EQ(estimate_run_memory(map) - estimate_run_memory(neat), 200 * kBytesPerMember);
}

}  // namespace
}  // namespace softevo::master
