// `softevo export` end to end on a tiny real run: the robot file is written atomically, an
// existing output is replaced only with --force, and symlinks or special files are refused with
// the target left as it was (docs/output-files.md). Every exported individual re-evaluates with
// `softevo eval` to its archived fitness, bit for bit (the file carries its run's config).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "common/eval_types.hpp"
#include "io/archive.hpp"
#include "tests/build_tree.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;
using test::binary;

std::uint64_t bits_of(double v) {
  return std::bit_cast<std::uint64_t>(v);
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class CmdExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(binary("softevo")) || !fs::exists(binary("softevo-mpi"))) return;
    if (!fs::exists("configs/quickstart.toml")) return;
    dir_ = fs::temp_directory_path() / ("softevo_test_cmd_export_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    archive_ = (dir_ / "run.h5").string();
    run_ = test::run_command(binary("softevo-mpi") +
                             " --config configs/quickstart.toml --seed 2 --generations 1 "
                             "--population 5 --set body.lattice=[4,4,4] "
                             "--set task.eval_seconds=0.5 --out " +
                             archive_);
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  void SetUp() override {
    if (archive_.empty()) GTEST_SKIP() << "softevo, softevo-mpi or configs/quickstart.toml missing";
    ASSERT_EQ(run_.code, 0) << run_.output;
  }
  static test::CommandResult export_to(const fs::path& out, const std::string& flags = "") {
    return test::run_command(binary("softevo") + " export " + archive_ + " --best -o " +
                             out.string() + " " + flags);
  }
  static inline fs::path dir_;
  static inline std::string archive_;
  static inline test::CommandResult run_;
};

TEST_F(CmdExport, ExistingOutputIsReplacedOnlyWithForce) {
  const fs::path out = dir_ / "best.json";
  const auto first = export_to(out);
  ASSERT_EQ(first.code, 0) << first.output;
  const std::string robot = read(out);
  EXPECT_NE(robot.find("softevo.robot/1"), std::string::npos);

  std::ofstream(out) << "my notes";
  const auto refused = export_to(out);
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_NE(refused.output.find("--force"), std::string::npos) << refused.output;
  EXPECT_EQ(read(out), "my notes");

  const auto forced = export_to(out, "--force");
  ASSERT_EQ(forced.code, 0) << forced.output;
  EXPECT_EQ(read(out), robot);
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

TEST_F(CmdExport, SymlinkAndSpecialTargetsAreRefused) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "precious";
  const fs::path link = dir_ / "link.json";
  fs::create_symlink(victim, link);
  const auto via_link = export_to(link, "--force");
  EXPECT_EQ(via_link.code, 2) << via_link.output;
  EXPECT_NE(via_link.output.find("symbolic link"), std::string::npos) << via_link.output;
  EXPECT_EQ(read(victim), "precious");
  EXPECT_TRUE(fs::is_symlink(link));

  const fs::path fifo = dir_ / "fifo.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto to_fifo = export_to(fifo, "--force");
  EXPECT_EQ(to_fifo.code, 2) << to_fifo.output;
  EXPECT_TRUE(fs::is_fifo(fifo));

  const auto to_device = export_to("/dev/full", "--force");
  EXPECT_EQ(to_device.code, 2) << to_device.output;
  EXPECT_NE(to_device.output.find("character device"), std::string::npos) << to_device.output;
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
}

TEST_F(CmdExport, EveryExportedIndividualReEvaluatesToItsArchivedFitnessBitForBit) {
  const io::Archive archive(archive_);
  const io::GenerationRecord generation = archive.generation(archive.generations().back());
  ASSERT_GE(generation.size(), 4u);
  for (std::size_t row = 0; row < generation.size(); ++row) {
    const fs::path out = dir_ / ("id" + std::to_string(generation.id[row]) + ".json");
    const auto exported = test::run_command(binary("softevo") + " export " + archive_ + " --id " +
                                            std::to_string(generation.id[row]) + " -o " +
                                            out.string() + " --force --json");
    ASSERT_EQ(exported.code, 0) << exported.output;
    const auto eval = test::run_command(binary("softevo") + " eval " + out.string() + " --json");
    ASSERT_EQ(eval.code, 0) << eval.output;
    const nlohmann::json j = nlohmann::json::parse(eval.output);
    EXPECT_EQ(j["config_source"], "robot") << eval.output;
    EXPECT_EQ(j["config_hash"], archive.info().config_hash);
    ASSERT_TRUE(j["fitness"].is_number()) << eval.output;
    EXPECT_EQ(bits_of(j["fitness"].get<double>()), bits_of(generation.fitness[row]))
        << "id " << generation.id[row] << ": eval " << j["fitness"] << ", archived "
        << generation.fitness[row];
    EXPECT_EQ(j["status"], to_string(static_cast<EvalStatus>(generation.status[row])));
    EXPECT_EQ(j["reproduces_archived_fitness"], true) << eval.output;
  }
  // --set overrides the robot file's config, and the output says so.
  const fs::path any = dir_ / ("id" + std::to_string(generation.id[0]) + ".json");
  const auto changed = test::run_command(binary("softevo") + " eval " + any.string() +
                                         " --set task.eval_seconds=0.25");
  ASSERT_EQ(changed.code, 0) << changed.output;
  EXPECT_NE(changed.output.find("run config (hash " + archive.info().config_hash),
            std::string::npos)
      << changed.output;
  EXPECT_NE(changed.output.find("1 --set override"), std::string::npos) << changed.output;
  EXPECT_EQ(changed.output.find("archived "), std::string::npos) << changed.output;
}

// A run with controller learning (docs/model.md §8.11): the archived fitness is the learned
// controller's, so export writes the learned robot, which `eval`s to it bit for bit; replay
// --verify re-simulates the learned robots; info reports what learning did.
TEST_F(CmdExport, LearnedRobotsReEvaluateToTheirArchivedFitness) {
  const std::string learn = (dir_ / "learn.h5").string();
  const auto run = test::run_command(
      binary("softevo-mpi") +
      " --config configs/quickstart.toml --seed 4 --generations 2 --population 4 "
      "--set body.lattice=[4,4,4] --set task.eval_seconds=0.3 --set learning.method=es "
      "--set learning.evaluations=5 --set learning.population=2 --out " +
      learn);
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_NE(run.output.find("learned "), std::string::npos) << run.output;
  const io::Archive archive(learn);
  EXPECT_EQ(archive.info().experiment, "gait-open-learn");
  const io::GenerationRecord generation = archive.generation(1);
  ASSERT_TRUE(generation.has_learning());
  for (std::size_t row = 0; row < generation.size(); ++row) {
    const fs::path out = dir_ / ("learn" + std::to_string(generation.id[row]) + ".json");
    const auto exported =
        test::run_command(binary("softevo") + " export " + learn + " --id " +
                          std::to_string(generation.id[row]) + " -o " + out.string() + " --force");
    ASSERT_EQ(exported.code, 0) << exported.output;
    const auto eval = test::run_command(binary("softevo") + " eval " + out.string() + " --json");
    ASSERT_EQ(eval.code, 0) << eval.output;
    const nlohmann::json j = nlohmann::json::parse(eval.output);
    EXPECT_EQ(bits_of(j["fitness"].get<double>()), bits_of(generation.fitness[row]))
        << "id " << generation.id[row];
    EXPECT_EQ(j["reproduces_archived_fitness"], true) << eval.output;
  }
  const auto replay = test::run_command(binary("softevo") + " replay " + learn + " --all --verify");
  EXPECT_EQ(replay.code, 0) << replay.output;
  EXPECT_NE(replay.output.find("0 mismatched"), std::string::npos) << replay.output;
  const auto info = test::run_command(binary("softevo") + " info " + learn);
  ASSERT_EQ(info.code, 0) << info.output;
  EXPECT_NE(info.output.find("learning         "), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("learned from "), std::string::npos) << info.output;
  const auto info_json = test::run_command(binary("softevo") + " info " + learn + " --json");
  const nlohmann::json j = nlohmann::json::parse(info_json.output);
  EXPECT_GT(j["learning"]["evaluations"].get<std::int64_t>(), 0);
  EXPECT_EQ(j["learning"]["iterations"], 2);
  EXPECT_TRUE(j["champion"].contains("fitness_before"));
}

// `softevo info` (the command a researcher reads a run with) counts the robots of each status and
// names the champion's.
TEST_F(CmdExport, InfoCountsRobotsPerStatusAndShowsTheChampionsStatus) {
  const auto r = test::run_command(binary("softevo") + " info " + archive_ + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  const io::Archive archive(archive_);
  std::map<std::string, std::int64_t> expected;
  std::int64_t rows = 0;
  for (const std::int64_t g : archive.generations())
    for (const std::uint8_t code : archive.generation(g).status) {
      ++expected[to_string(static_cast<EvalStatus>(code))];
      ++rows;
    }
  std::int64_t counted = 0;
  for (const auto& [name, n] : j["status_counts"].items()) {
    counted += n.get<std::int64_t>();
    EXPECT_EQ(n.get<std::int64_t>(), expected[name]) << name;
  }
  EXPECT_EQ(counted, rows);
  for (const char* name : {"ok", "killed: flipped", "killed: exploded", "diverged", "failed"})
    EXPECT_TRUE(j["status_counts"].contains(name)) << name;
  ASSERT_TRUE(j["champion"].is_object()) << r.output;
  EXPECT_TRUE(j["champion"]["status"].is_string());
  const auto text = test::run_command(binary("softevo") + " info " + archive_);
  EXPECT_NE(text.output.find("champion         generation"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("robots           ok "), std::string::npos) << text.output;
}

TEST_F(CmdExport, TheDefaultIsTheBestAndTheOldSpellingStillWorks) {
  const fs::path out = dir_ / "default.json";
  const auto r = test::run_command(binary("softevo") + " export " + archive_ + " --out " +
                                   out.string() + " --force --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  const io::Archive archive(archive_);
  const io::GenerationRecord generation = archive.generation(archive.generations().back());
  double best = generation.fitness[0];
  for (const double f : generation.fitness) best = std::max(best, f);
  EXPECT_EQ(bits_of(j["fitness"].get<double>()), bits_of(best));
}

// A generation that is not there names those that are (issue 39), and prints the fitness in its
// shortest round-trip form, as Python does.
TEST_F(CmdExport, AMissingGenerationNamesTheOnesThatExistAndFitnessIsShortest) {
  const io::Archive archive(archive_);
  const std::vector<std::int64_t> gens = archive.generations();
  const auto r = test::run_command(binary("softevo") + " export " + archive_ +
                                   " --generation 99 --out " + (dir_ / "x.json").string());
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("no generation 99"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the archive has generations " + std::to_string(gens.front()) + ".." +
                          std::to_string(gens.back())),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "x.json"));
  const auto text = test::run_command(binary("softevo") + " export " + archive_ + " --out " +
                                      (dir_ / "y.json").string());
  ASSERT_EQ(text.code, 0) << text.output;
  const io::GenerationRecord last = archive.generation(gens.back());
  double best = last.fitness[0];
  for (const double f : last.fitness) best = std::max(best, f);
  char shortest[32];
  const auto end = std::to_chars(shortest, shortest + sizeof shortest, best).ptr;
  EXPECT_NE(text.output.find("fitness " + std::string(shortest, end) + " ("), std::string::npos)
      << text.output;
}

// --id alone takes the individual from the last generation that holds it: an id of generation
// 0 that later generations dropped is exported without --generation (before: "generation 2 has
// no individual with id ..."); with a --generation that lacks it, the error names where it is.
TEST_F(CmdExport, AnIdAloneComesFromTheLastGenerationThatHoldsIt) {
  const std::string source =
      std::getenv("SOFTEVO_SOURCE_DIR") ? std::getenv("SOFTEVO_SOURCE_DIR") : ".";
  const std::string run = (dir_ / "three.h5").string();
  const auto evolved = test::run_command(binary("softevo") + " evolve --progress never --config " +
                                         source + "/tests/data/tiny-run.toml --out " + run);
  ASSERT_EQ(evolved.code, 0) << evolved.output;
  const io::Archive archive(run);
  const std::vector<std::int64_t> gens = archive.generations();
  ASSERT_EQ(gens.size(), 3u);
  // The last generation holding each id of generation 0, counted here from the records.
  std::map<std::int64_t, std::int64_t> last_holding;
  for (const std::int64_t g : gens)
    for (const std::int64_t id : archive.generation(g).id) last_holding[id] = g;
  std::int64_t dropped = -1;
  for (const std::int64_t id : archive.generation(0).id)
    if (last_holding[id] < gens.back()) dropped = id;
  ASSERT_GE(dropped, 0) << "every individual of generation 0 survived to the last";
  const fs::path out = dir_ / "dropped.json";
  const auto exported =
      test::run_command(binary("softevo") + " export " + run + " --id " + std::to_string(dropped) +
                        " -o " + out.string() + " --json");
  ASSERT_EQ(exported.code, 0) << exported.output;
  EXPECT_EQ(nlohmann::json::parse(exported.output)["generation"], last_holding[dropped])
      << exported.output;
  const auto missing = test::run_command(
      binary("softevo") + " export " + run + " --id " + std::to_string(dropped) + " --generation " +
      std::to_string(gens.back()) + " -o " + (dir_ / "none.json").string());
  EXPECT_EQ(missing.code, 2) << missing.output;
  EXPECT_NE(missing.output.find("has no individual with id " + std::to_string(dropped) +
                                "; it is in generation"),
            std::string::npos)
      << missing.output;
  EXPECT_FALSE(fs::exists(dir_ / "none.json"));
}

TEST_F(CmdExport, SoftevoMpiHasAVersionAndTheOutputSpellings) {
  const auto version = test::run_command(binary("softevo-mpi") + " --version");
  EXPECT_EQ(version.code, 0) << version.output;
  EXPECT_EQ(version.output.rfind("softevo-mpi ", 0), 0u) << version.output;
  const auto help = test::run_command(binary("softevo-mpi") + " --help");
  for (const char* flag : {"-o,--output,--out", "--progress", "-q,--quiet", "-v,--verbose"})
    EXPECT_NE(help.output.find(flag), std::string::npos) << flag << "\n" << help.output;
  const auto bad = test::run_command(binary("softevo-mpi") + " --progress sometimes");
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_EQ(bad.output.rfind("softevo-mpi: error: ", 0), 0u) << bad.output;
}

TEST_F(CmdExport, AnEditedEvaluationConfigIsRefused) {
  const fs::path out = dir_ / "edited.json";
  ASSERT_EQ(export_to(out, "--force").code, 0);
  std::string text = read(out);
  const std::size_t at = text.find("eval_seconds = ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 15, "eval_seconds = 9");
  std::ofstream(out, std::ios::trunc) << text;
  const auto r = test::run_command(binary("softevo") + " eval " + out.string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("evaluation.config_hash"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace softevo
