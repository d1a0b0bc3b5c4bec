// Determinism (docs/model.md §9): the same robot file gives bit-identical fitness in different
// processes, including closed-loop multi-chamber robots (whose first sensor reading was
// uninitialised memory in the thesis simulator, §3.7).
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/robot.hpp"
#include "physics/model.hpp"
#include "tests/test_controller_spec.hpp"

namespace fs = std::filesystem;

namespace {

fs::path shared_dir() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  return (env ? fs::path(env) : fs::current_path()) / ".." / "shared";
}

std::string run(const std::string& robot, const std::string& seconds,
                const std::string& simd = "") {
  const std::string cmd =
      std::string(SOFTEVO_EVAL_FITNESS_EXE) + " '" + robot + "' " + seconds + " " + simd;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return "popen failed";
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  const int rc = pclose(pipe);
  return rc == 0 ? out : "exit " + std::to_string(rc) + ": " + out;
}

// A closed-loop directed robot with two chambers, written as a robot file named after the
// calling test (ctest runs the tests of this file in parallel processes).
std::string write_closed_loop_robot() {
  softevo::RobotFile r;
  r.name = "determinism-closed";
  r.body.lattice = {7, 4, 4};
  r.body.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) r.body.materials.push_back({1.0e4 * k, 1000.0});
  r.body.cells.assign(7 * 4 * 4, 7);
  for (int y = 1; y <= 2; ++y)
    for (int z = 1; z <= 2; ++z) {
      r.body.cells[r.body.cell_index(1, y, z)] = 11;
      r.body.cells[r.body.cell_index(4, y, z)] = 12;
      r.body.cells[r.body.cell_index(5, y, z)] = 12;
    }
  r.controller = softevo::test::make_controller(
      true, true, [](int i) { return std::cos(0.5 + 2.1 * i); }, 2.5);
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  // The pid keeps concurrent runs of the suite (several build trees on one machine) apart.
  const fs::path path = fs::temp_directory_path() / ("softevo_determinism_" + test + "_" +
                                                     std::to_string(::getpid()) + ".robot.json");
  softevo::write_robot_file(r, path.string());
  return path.string();
}

}  // namespace

TEST(EvalDeterminism, SyntheticClosedLoopRobotInTwoProcesses) {
  const std::string robot = write_closed_loop_robot();
  const std::string a = run(robot, "0.5"), b = run(robot, "0.5");
  fs::remove(robot);
  EXPECT_EQ(a, b);
  EXPECT_NE(a.find(" ok"), std::string::npos) << a;
}

// The wide SIMD widths this CPU and build run (besides sse2, which always runs).
std::vector<std::string> wide_widths() {
  std::vector<std::string> widths;
  for (auto simd : {softevo::physics::Simd::avx2, softevo::physics::Simd::avx512})
    if (softevo::physics::simd_supported(simd)) widths.push_back(softevo::to_string(simd));
  return widths;
}

// The SIMD width of the physics passes does not change a single bit of a whole evaluation
// (links in both angle modes, floor, friction, self-collision, pneumatics, closed loop).
TEST(EvalDeterminism, SameBitsAtEverySimdWidth) {
  if (wide_widths().empty())
    GTEST_SKIP() << "no wide SIMD width here (CPU or build): only SSE2 runs";
  const std::string robot = write_closed_loop_robot();
  const std::string narrow = run(robot, "1", "sse2");
  EXPECT_NE(narrow.find(" ok"), std::string::npos) << narrow;
  for (const std::string& wide : wide_widths()) EXPECT_EQ(narrow, run(robot, "1", wide)) << wide;
  fs::remove(robot);
}

// The same for a thesis champion whose body bends many links into large-angle mode.
TEST(EvalDeterminism, ChampionSameBitsAtEverySimdWidth) {
  if (wide_widths().empty())
    GTEST_SKIP() << "no wide SIMD width here (CPU or build): only SSE2 runs";
  const fs::path champion = shared_dir() / "reference" / "bestbots" / "gait-open-05.robot.json";
  if (!fs::exists(champion)) GTEST_SKIP() << "../shared not found (" << champion << ")";
  const std::string narrow = run(champion.string(), "1", "sse2");
  EXPECT_NE(narrow.find(" ok"), std::string::npos) << narrow;
  for (const std::string& wide : wide_widths())
    EXPECT_EQ(narrow, run(champion.string(), "1", wide)) << wide;
}

TEST(EvalDeterminism, FiveChamberClosedLoopChampionInTwoProcesses) {
  // gait-closed-10: 5 chambers, closed loop; the thesis simulator gave 29.65 / 182.97 / 29.65 in
  // three runs of the same file (§3.7). Here: identical bits in every process.
  const fs::path robot = shared_dir() / "reference" / "bestbots" / "gait-closed-10.robot.json";
  if (!fs::exists(robot)) GTEST_SKIP() << "../shared not found (" << robot << ")";
  const std::string a = run(robot.string(), "1"), b = run(robot.string(), "1");
  EXPECT_EQ(a, b);
  EXPECT_NE(a.find(" ok"), std::string::npos) << a;
}
