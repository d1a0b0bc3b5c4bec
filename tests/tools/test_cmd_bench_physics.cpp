// `softevo bench physics` end to end on its smallest scene: the JSON rows carry microseconds per
// voxel-step, and with --cycles the measured clock (before, after and their mean) and the same
// figure in cycles per voxel-step at that clock; the table then has the cycles column and names
// the clock. --scene blockXxYxZ runs a solid block of that size; a scene that is neither named nor
// such a block, or a block out of range, is a usage error that says why. --batch gives a row per
// number of lanes (1, 4, 5, 8, 10, 16) with microseconds per voxel-step per evaluation; --robot
// adds a robot's body and needs --batch.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/build_tree.hpp"

namespace softevo {
namespace {

using test::binary;
using test::run_command;

const std::string kSmallRun = " bench physics --scene block4x4x4 --steps 20 --runs 1 --simd scalar";

class CmdBenchPhysics : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(binary("softevo")))
      GTEST_SKIP() << "softevo not built: " << binary("softevo");
  }
};

TEST_F(CmdBenchPhysics, RowsGiveMicrosecondsPerVoxelStepWithoutAClockUnlessAsked) {
  const auto r = run_command(binary("softevo") + kSmallRun + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json rows = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  ASSERT_EQ(rows.size(), 2u) << "one row per integrator";
  for (const nlohmann::json& row : rows) {
    EXPECT_EQ(row["voxels"], 64);
    EXPECT_EQ(row["steps"], 20);
    const double cpu = row["cpu_seconds"].get<double>();
    ASSERT_GT(cpu, 0.0);
    EXPECT_DOUBLE_EQ(row["us_per_voxel_step"].get<double>(), cpu * 1e6 / (20.0 * 64));
    EXPECT_FALSE(row.contains("cycles_per_voxel_step"));
  }
}

TEST_F(CmdBenchPhysics, ABlockOfAnySizeIsAScene) {
  const auto r = run_command(binary("softevo") +
                             " bench physics --scene block3x2x5 --steps 10 --runs 1 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json rows = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  ASSERT_EQ(rows.size(), 2u) << "one row per integrator";
  for (const nlohmann::json& row : rows) {
    EXPECT_EQ(row["scene"], "block3x2x5");
    EXPECT_EQ(row["voxels"], 30);
    // links between face neighbours: (X-1)YZ + X(Y-1)Z + XY(Z-1)
    EXPECT_EQ(row["links"], 2 * 2 * 5 + 3 * 1 * 5 + 3 * 2 * 4);
    EXPECT_EQ(row["failed_steps"], 0);
  }
}

TEST_F(CmdBenchPhysics, AnUnknownSceneOrABlockOutOfRangeIsAUsageError) {
  for (const char* scene : {"block3x3", "block-3x3x3", "block3x3x3x", "torus"}) {
    const auto r = run_command(binary("softevo") + " bench physics --steps 1 --runs 1 --scene '" +
                               scene + "'");
    EXPECT_EQ(r.code, 2) << scene << ": " << r.output;
    EXPECT_NE(r.output.find("matches no scene"), std::string::npos) << r.output;
  }
  for (const char* scene : {"block0x3x3", "block47x47x47", "block99999999999999999999999x1x1"}) {
    const auto r = run_command(binary("softevo") + " bench physics --steps 1 --runs 1 --scene '" +
                               scene + "'");
    EXPECT_EQ(r.code, 2) << scene << ": " << r.output;
    EXPECT_NE(r.output.find("at most 100000 voxels"), std::string::npos) << r.output;
  }
}

TEST_F(CmdBenchPhysics, TheBatchedSceneHasARowPerLaneCountPerEvaluation) {
  const auto r = run_command(binary("softevo") + kSmallRun + " --batch --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json rows = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  ASSERT_EQ(rows.size(), 6u) << "one row per lane count";
  const int lanes[] = {1, 4, 5, 8, 10, 16};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const nlohmann::json& row = rows[i];
    EXPECT_EQ(row["lanes"], lanes[i]);
    EXPECT_EQ(row["integrator"], "pneuvox");
    EXPECT_EQ(row["failed_steps"], 0);
    const double cpu = row["cpu_seconds"].get<double>();
    EXPECT_DOUBLE_EQ(row["us_per_voxel_step"].get<double>(), cpu * 1e6 / (20.0 * 64 * lanes[i]));
  }
}

TEST_F(CmdBenchPhysics, ARobotWithoutBatchIsAUsageError) {
  const auto r =
      run_command(binary("softevo") + kSmallRun + " --robot robots/gait-open-walker.robot.json");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--robot needs --batch"), std::string::npos) << r.output;
}

TEST_F(CmdBenchPhysics, ARobotsBodyIsABatchedScene) {
  const auto r = run_command(binary("softevo") +
                             " bench physics --scene block4x4x4 --steps 2 --runs 1 --simd scalar "
                             "--batch --json --robot robots/gait-open-walker.robot.json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json rows = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  ASSERT_EQ(rows.size(), 12u) << "the block's 6 rows, then the robot's";
  EXPECT_EQ(rows[6]["scene"], "gait-open_seed3_gen4_id90");  // the robot file's name
  EXPECT_EQ(rows[11]["lanes"], 16);
}

#if defined(__x86_64__) || defined(__aarch64__)
TEST_F(CmdBenchPhysics, CyclesAreTheTimeAtTheMeanOfTheClockMeasuredBeforeAndAfter) {
  const auto r = run_command(binary("softevo") + kSmallRun + " --cycles --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json rows = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  ASSERT_EQ(rows.size(), 2u);
  for (const nlohmann::json& row : rows) {
    const double before = row["clock_ghz_before"].get<double>();
    const double after = row["clock_ghz_after"].get<double>();
    const double clock = row["clock_ghz"].get<double>();
    // No bound on the figure itself: a test assumes neither the machine's speed nor its load
    // (a fixed range failed on an Intel Sapphire Rapids core, issue 39).
    EXPECT_TRUE(std::isfinite(before) && before > 0.0) << before;
    EXPECT_TRUE(std::isfinite(after) && after > 0.0) << after;
    EXPECT_EQ(row["clock_method"], "dependent register additions");
    ASSERT_TRUE(row.contains("clock_ghz_os")) << "the OS's figure, or null where it has none";
    if (row["clock_ghz_os"].is_null()) {
      EXPECT_FALSE(row["clock_os_disagrees"].get<bool>());
    } else {
      const double os = row["clock_ghz_os"].get<double>();
      EXPECT_GT(os, 0.0);
      EXPECT_EQ(row["clock_os_disagrees"].get<bool>(), std::fabs(os - clock) > 0.1 * clock);
    }
    EXPECT_DOUBLE_EQ(clock, 0.5 * (before + after));
    EXPECT_NEAR(row["cycles_per_voxel_step"].get<double>(),
                row["us_per_voxel_step"].get<double>() * 1e3 * clock,
                1e-9 * row["cycles_per_voxel_step"].get<double>());
  }
  const auto table = run_command(binary("softevo") + kSmallRun + " --cycles");
  ASSERT_EQ(table.code, 0) << table.output;
  EXPECT_NE(table.output.find("cycles/v-s"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("core clock"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("operating system"), std::string::npos)
      << "the cross-check is reported either way: " << table.output;
  EXPECT_NE(table.output.find("block4x4x4"), std::string::npos) << table.output;
}
#endif

}  // namespace
}  // namespace softevo
