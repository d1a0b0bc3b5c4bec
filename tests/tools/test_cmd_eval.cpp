// `softevo eval ROBOT.json [--task] [--seconds] [--simd] [--json]` end to end (issue 4): the JSON
// object carries the named fields with sensible values, the directed task reports five
// directions, --simd changes only the reported width, and a malformed robot file stops with an
// error naming the file and the key.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/config_identity.hpp"
#include "common/robot.hpp"
#include "tests/build_tree.hpp"
#include "tests/test_controller_spec.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;

using test::binary;
using test::run_command;

// A 6x3x3 closed-loop directed robot of one material with a two-cell chamber.
fs::path write_robot(const fs::path& dir, const std::string& name = "cmd-eval") {
  RobotFile r;
  r.name = name;
  r.body.lattice = {6, 3, 3};
  r.body.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) r.body.materials.push_back({1.0e4 * k, 1000.0});
  r.body.cells.assign(6 * 3 * 3, 5);
  r.body.cells[r.body.cell_index(2, 1, 1)] = 11;
  r.body.cells[r.body.cell_index(3, 1, 1)] = 11;
  r.controller = test::make_controller(
      true, true, [](int i) { return std::sin(0.3 + 1.7 * i); }, 2.0);
  const fs::path path = dir / (name == "cmd-eval" ? "robot.json" : "named.json");
  write_robot_file(r, path.string());
  return path;
}

class CmdEval : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(binary("softevo"))) GTEST_SKIP() << "softevo not built: " << binary("softevo");
    dir_ = test::fresh_test_dir("cmd_eval");
    robot_ = write_robot(dir_);
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  fs::path dir_, robot_;
};

// A robot file whose run config holds a 50,000-digit number or an inline table 10,000 deep: a
// clear error naming the limit, never a crash (issue 39: the config reader's recursion overflowed
// the stack in every command that reads the robot file).
TEST_F(CmdEval, AHostileConfigInsideARobotFileIsAnError) {
  RobotFile robot = read_robot_file(robot_.string());
  std::string deep = "x = ";
  for (int i = 0; i < 10000; ++i) deep += "{a=";
  for (const std::string& line : {"seed = " + std::string(50000, '7'), deep}) {
    RobotEvaluation& evaluation = robot.evaluation.emplace();
    evaluation.config = "[run]\n" + line + "\n";
    evaluation.config_hash = hash_hex(text_hash(evaluation.config));
    const fs::path path = dir_ / "hostile.json";
    write_robot_file(robot, path.string(), Overwrite::replace);
    const std::string page = (dir_ / "page.html").string();
    const std::string picture = (dir_ / "picture.png").string();
    for (const std::string& command : {std::string(" eval "), " render -o '" + picture + "' ",
                                       " view --export-html '" + page + "' "}) {
      const auto r = run_command(binary("softevo") + command + "'" + path.string() + "'");
      EXPECT_TRUE(r.code == 1 || r.code == 2) << command << " exit " << r.code << ": " << r.output;
      EXPECT_TRUE(r.output.find("a config line may be at most 10000 bytes") != std::string::npos ||
                  r.output.find("nested more than 8 deep") != std::string::npos)
          << command << ": " << r.output;
    }
  }
}

TEST_F(CmdEval, GaitJsonHasTheNamedFields) {
  const auto r = run_command(binary("softevo") + " eval '" + robot_.string() +
                             "' --task gait --seconds 0.5 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  for (const char* key : {"fitness", "status", "components", "sim_seconds", "steps", "voxels",
                          "chambers", "wall_seconds", "simd"})
    EXPECT_TRUE(j.contains(key)) << key << " missing in " << r.output;
  EXPECT_TRUE(j["fitness"].is_number());
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["task"], "gait");
  ASSERT_EQ(j["components"].size(), 1u);
  // The archive's column names (docs/archive.md), nothing else.
  std::vector<std::string> keys;
  const auto ordered = nlohmann::ordered_json::parse(r.output);
  for (const auto& item : ordered["components"][0].items()) keys.push_back(item.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"fitness", "distance", "status"}));
  EXPECT_NEAR(j["sim_seconds"].get<double>(), 0.5, 1.0 / 60.0);
  EXPECT_GT(j["steps"].get<long long>(), 0);
  EXPECT_EQ(j["voxels"], 6 * 3 * 3 - 2);
  EXPECT_EQ(j["chambers"], 1);
  EXPECT_GE(j["wall_seconds"].get<double>(), 0.0);
  EXPECT_TRUE(j["simd"] == "sse2" || j["simd"] == "avx2" || j["simd"] == "avx512") << j["simd"];
}

TEST_F(CmdEval, DirectedJsonReportsFiveDirections) {
  const auto r = run_command(binary("softevo") + " eval '" + robot_.string() +
                             "' --task directed --seconds 0.25 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j["components"].size(), 5u);
  for (const auto& c : j["components"])
    for (const char* key : {"fitness", "direction_deg", "distance", "path_length", "angle_error",
                            "perpendicular_penalty", "status"})
      EXPECT_TRUE(c.contains(key)) << key;
}

TEST_F(CmdEval, RotateJsonNamesItsComponents) {
  const auto r = run_command(binary("softevo") + " eval '" + robot_.string() +
                             "' --task rotate --seconds 0.25 --set task.rotate_travel_penalty=0.5"
                             " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["task"], "rotate");
  ASSERT_EQ(j["component_names"].size(), 3u);
  EXPECT_EQ(j["component_names"][0]["name"], "heading_change");
  EXPECT_EQ(j["component_names"][0]["unit"], "rad");
  ASSERT_EQ(j["components"].size(), 1u);
  const auto& c = j["components"][0];
  for (const char* key : {"heading_change", "travel", "travel_penalty", "fitness", "status"})
    EXPECT_TRUE(c.contains(key)) << key << " missing in " << r.output;
  if (j["status"] == "ok") {
    // F = |heading change| - penalty, in the reported components.
    EXPECT_DOUBLE_EQ(j["fitness"].get<double>(), std::fabs(c["heading_change"].get<double>()) -
                                                     c["travel_penalty"].get<double>());
    EXPECT_DOUBLE_EQ(c["travel_penalty"].get<double>(), 0.5 * c["travel"].get<double>());
  }
}

// --simd picks the width of the physics passes: the same fitness bits at sse2 as at the best
// width, the width used is reported, and an unknown width is a usage error.
TEST_F(CmdEval, SimdWidthChangesNothingButTheReportedWidth) {
  const std::string eval =
      binary("softevo") + " eval '" + robot_.string() + "' --seconds 0.3 --json";
  const auto best = run_command(eval);
  const auto narrow = run_command(eval + " --simd sse2");
  ASSERT_EQ(best.code, 0) << best.output;
  ASSERT_EQ(narrow.code, 0) << narrow.output;
  const nlohmann::json jb = nlohmann::json::parse(best.output);
  const nlohmann::json jn = nlohmann::json::parse(narrow.output);
  EXPECT_EQ(jn["simd"], "sse2");
  EXPECT_EQ(jn["fitness"].get<double>(), jb["fitness"].get<double>()) << jb["simd"];
  EXPECT_EQ(jn["steps"], jb["steps"]);
  const auto bad = run_command(eval + " --simd avx");
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--simd"), std::string::npos) << bad.output;
}

TEST_F(CmdEval, RobotNameIsPrintedWithControlCharactersEscaped) {
  // A name that would clear the screen and set the window title if printed raw.
  const fs::path robot = write_robot(dir_, "evil\x1b[2J\x1b]0;owned\x07");
  const auto r = run_command(binary("softevo") + " eval '" + robot.string() + "' --seconds 0.1");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find('\x1b'), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("robot        evil\\x1b[2J\\x1b]0;owned\\x07"), std::string::npos)
      << r.output;
}

TEST_F(CmdEval, MalformedRobotFileNamesFileAndKey) {
  nlohmann::json robot;
  std::ifstream(robot_) >> robot;
  robot.erase("lattice");
  const fs::path bad = dir_ / "bad.robot.json";
  std::ofstream(bad) << robot.dump();
  const auto r = run_command(binary("softevo") + " eval '" + bad.string() + "' --json");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(bad.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("lattice"), std::string::npos) << r.output;
}

// Issue 21 item 6: option values get the config's range checks, naming the key (before: nan
// silently ran 10 s, 1e308 reported "ok" after 0 steps, 1e10 failed with "vector::reserve",
// 1e999 "got a string").
TEST_F(CmdEval, OutOfRangeSecondsAndDirectionAreConfigErrorsNamingTheKey) {
  const std::string eval = binary("softevo") + " eval '" + robot_.string() + "' --task directed";
  for (const char* seconds : {"nan", "1e308", "1e10", "-1", "0"}) {
    const auto r = run_command(eval + " --seconds " + seconds);
    EXPECT_EQ(r.code, 2) << seconds << ": " << r.output;
    EXPECT_NE(r.output.find("task.eval_seconds = "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("is out of range"), std::string::npos) << r.output;
  }
  const auto huge = run_command(eval + " --set task.eval_seconds=1e999");
  EXPECT_EQ(huge.code, 2) << huge.output;
  EXPECT_NE(huge.output.find("task.eval_seconds = 1e999 is out of range"), std::string::npos)
      << huge.output;
  const auto direction = run_command(eval + " --seconds 0.1 --direction nan");
  EXPECT_EQ(direction.code, 2) << direction.output;
  EXPECT_NE(direction.output.find("task.directions[0] = nan is out of range"), std::string::npos)
      << direction.output;
  // --direction and --timeout are numbers, as render's and view's --direction (issue 39).
  for (const char* option : {"--direction north", "--timeout soon", "--direction [90,0]"}) {
    const auto text = run_command(eval + " --seconds 0.1 " + option);
    EXPECT_EQ(text.code, 2) << option << ": " << text.output;
    EXPECT_NE(text.output.find("Could not convert: "), std::string::npos) << text.output;
  }
  const auto timeout = run_command(eval + " --seconds 0.1 --timeout 1e10");
  EXPECT_EQ(timeout.code, 2) << timeout.output;
  EXPECT_NE(timeout.output.find("run.eval_timeout_seconds = "), std::string::npos)
      << timeout.output;
}

// The work of one evaluation is bounded: the step limits (a 1e-6 m voxel needs about a million
// steps per control frame) and the wall-clock deadline --timeout, each a status.
TEST_F(CmdEval, WorkIsBoundedByTheStepLimitsAndTimeout) {
  nlohmann::json robot;
  std::ifstream(robot_) >> robot;
  robot["voxel_size"] = 1e-6;
  const fs::path tiny = dir_ / "tiny.json";
  std::ofstream(tiny) << robot.dump();
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = run_command(binary("softevo") + " eval '" + tiny.string() + "' --json");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
  ASSERT_EQ(r.code, 2) << r.output;  // status failed
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["status"], "failed");
  EXPECT_EQ(j["steps"], 0);
  EXPECT_NE(j["message"].get<std::string>().find("more than the limit of 100000"),
            std::string::npos)
      << r.output;
  const auto slow = run_command(binary("softevo") + " eval '" + robot_.string() +
                                "' --seconds 20 --timeout 1e-6 --json");
  ASSERT_EQ(slow.code, 0) << slow.output;
  const nlohmann::json js = nlohmann::json::parse(slow.output);
  EXPECT_EQ(js["status"], "timeout");
  EXPECT_LT(js["sim_seconds"].get<double>(), 1.0);
}

TEST_F(CmdEval, EmptyBodyNamesTheCause) {
  nlohmann::json robot;
  std::ifstream(robot_) >> robot;
  for (auto& cell : robot["cells"]) cell = cell.get<int>() >= 11 ? cell.get<int>() : 0;
  const fs::path chambers_only = dir_ / "chambers.json";
  std::ofstream(chambers_only) << robot.dump();
  const auto r = run_command(binary("softevo") + " eval '" + chambers_only.string() + "' --json");
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["status"], "invalid body") << r.output;
  EXPECT_EQ(j["message"], "body has only chamber cells, no structural voxel (material 1..10)");
}

// docs/output-files.md rule 3: an existing trace is replaced only with --force, and the check
// comes before the simulation.
TEST_F(CmdEval, ExistingTraceIsReplacedOnlyWithForce) {
  const fs::path trace = dir_ / "trace.h5";
  std::ofstream(trace) << "precious";
  const std::string eval = binary("softevo") + " eval '" + robot_.string() +
                           "' --seconds 0.1 --trace '" + trace.string() + "'";
  const auto refused = run_command(eval);
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_NE(refused.output.find("refusing to overwrite an existing file (pass --force"),
            std::string::npos)
      << refused.output;
  EXPECT_EQ(refused.output.find("fitness"), std::string::npos) << "simulated before refusing";
  EXPECT_EQ(fs::file_size(trace), 8u);
  const auto forced = run_command(eval + " --force");
  EXPECT_EQ(forced.code, 0) << forced.output;
  EXPECT_GT(fs::file_size(trace), 8u);
}

// Issue 22: one CLI convention: --version, a suggestion for a mistyped command, one error
// prefix for CLI11's errors and softevo's own.
TEST(SoftevoCli, VersionTyposAndErrorsFollowOneConvention) {
  const auto version = run_command(binary("softevo") + " --version");
  EXPECT_EQ(version.code, 0) << version.output;
  EXPECT_EQ(version.output.rfind("softevo ", 0), 0u) << version.output;
  const auto typo = run_command(binary("softevo") + " infoo x.h5");
  EXPECT_EQ(typo.code, 2) << typo.output;
  EXPECT_NE(typo.output.find("softevo: error: unknown command 'infoo', did you mean info?"),
            std::string::npos)
      << typo.output;
  // (not "frobnicate": since `softevo fabricate` it is a typo of that)
  const auto far_off = run_command(binary("softevo") + " xylophone");
  EXPECT_EQ(far_off.code, 2) << far_off.output;
  EXPECT_EQ(far_off.output.find("did you mean"), std::string::npos) << far_off.output;
  const auto missing = run_command(binary("softevo") + " eval");
  EXPECT_EQ(missing.code, 2) << missing.output;
  EXPECT_EQ(missing.output.rfind("softevo: error: ", 0), 0u) << missing.output;
  const auto bad_file = run_command(binary("softevo") + " eval /nonexistent/robot.json");
  EXPECT_EQ(bad_file.code, 2) << bad_file.output;
  EXPECT_EQ(bad_file.output.rfind("softevo: error: ", 0), 0u) << bad_file.output;
}

// Issue 30: one option vocabulary. Suggestions for mistyped options and transposed commands,
// ranges checked (a negative count is not "the config's"), -o/--output with --out, --json on
// config show, --seconds of one type, the help naming softevo-mpi, and a file of the wrong kind
// named for what it is.
TEST_F(CmdEval, OneOptionVocabularyAcrossCommands) {
  const std::string softevo = binary("softevo");
  const auto expect = [](const test::CommandResult& r, int code, const std::string& text) {
    EXPECT_EQ(r.code, code) << r.output;
    EXPECT_NE(r.output.find(text), std::string::npos) << r.output;
  };
  expect(run_command(softevo + " inof x.h5"), 2, "unknown command 'inof', did you mean info?");
  expect(run_command(softevo + " info x.h5 --jsno"), 2,
         "unknown option --jsno, did you mean --json?");
  expect(run_command(softevo + " evolve --progres never"), 2,
         "unknown option --progres, did you mean --progress?");
  expect(run_command(softevo + " evolve --generations -5"), 2,
         "--generations: -5 is not an integer >= 1");
  expect(run_command(softevo + " evolve --population 0"), 2,
         "--population: 0 is not an integer >= 1");
  expect(run_command(softevo + " export x.h5 --generation -1 -o x.json"), 2,
         "--generation: -1 is not an integer >= 0");
  // render takes --out as every other writer does: the error is about the input, not --out.
  expect(run_command(softevo + " render " + (dir_ / "none.json").string() + " --out " +
                     (dir_ / "x.png").string()),
         2, "none.json");
  // The tests run in the source tree.
  const auto shown =
      run_command(softevo + " config show configs/quickstart.toml --set neat.pop_size=7 --json");
  ASSERT_EQ(shown.code, 0) << shown.output;
  const auto j = nlohmann::json::parse(shown.output);
  EXPECT_EQ(j["config"]["neat"]["pop_size"], 7);
  EXPECT_EQ(j["config_hash"].get<std::string>().size(), 16u);
  for (const char* command : {"eval", "render"}) {
    const auto help = run_command(softevo + " " + command + " --help");
    EXPECT_NE(help.output.find("--seconds FLOAT"), std::string::npos) << command << help.output;
  }
  expect(run_command(softevo + " eval " + robot_.string() + " --seconds 1e10"), 2,
         "task.eval_seconds = 1e10 is out of range");
  const auto help = run_command(softevo + " --help");
  expect(help, 0, "evolve");
  expect(help, 0, "softevo-mpi");
  // view: --json says what --export-html wrote (on start, the server's url and port).
  if (run_command(softevo + " view --help").code == 0) {
    const fs::path html = dir_ / "page.html";
    const auto page = run_command(softevo + " view " + robot_.string() +
                                  " --seconds 0.2 --json --export-html " + html.string());
    // Without the page's npm packages (`npm ci` in view/web) there is no page to write.
    if (page.output.find("npm ci") == std::string::npos) {
      ASSERT_EQ(page.code, 0) << page.output;
      const auto v = nlohmann::json::parse(page.output);
      EXPECT_EQ(v["html"], html.string());
      EXPECT_EQ(v["bytes"].get<std::uintmax_t>(), fs::file_size(html));
    }
  }
  // A file of the wrong kind says what it is and which command takes it.
  expect(run_command(softevo + " info " + robot_.string()), 2,
         "not a run archive: it is JSON text, a robot file");
  const fs::path hdf5 = dir_ / "fake.h5";
  std::ofstream(hdf5, std::ios::binary) << std::string("\x89HDF\r\n\x1a\n", 8) << "rest";
  expect(run_command(softevo + " eval " + hdf5.string()), 2,
         "not a robot file: it is an HDF5 file (a run archive or a trace); `softevo export");
}

}  // namespace
}  // namespace softevo
