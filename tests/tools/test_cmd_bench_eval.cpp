// `softevo bench eval DIR [--runs N] [--json]` (issue 4's speed benchmark) end to end on a small
// gait robot with a recorded reference time: the JSON carries the run count and the per-robot
// figures, the speed-up is the reference time over ours, directed robots are left out, and a
// run count out of range is a usage error.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "common/robot.hpp"
#include "tests/build_tree.hpp"
#include "tests/test_controller_spec.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;

using test::binary;
using test::run_command;

constexpr double kReferenceCpuSeconds = 12.5;

// A 5x3x3 open-loop robot (gait or directed controller) with a one-cell chamber inside and a
// recorded thesis CPU time; it is not killed during the 10 s evaluation.
void write_bench_robot(const fs::path& path, const std::string& name, bool directed) {
  RobotFile r;
  r.name = name;
  r.body.lattice = {5, 3, 3};
  r.body.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) r.body.materials.push_back({1.0e4 * k, 1000.0});
  r.body.cells.assign(5 * 3 * 3, 5);
  r.body.cells[r.body.cell_index(2, 1, 1)] = 11;
  r.controller = test::make_controller(
      false, directed, [](int i) { return std::cos(0.5 + 1.3 * i); }, 1.5);
  r.reference_json = R"({"fitness": 1.0, "cpu_seconds": 12.5})";
  write_robot_file(r, path.string());
}

class CmdBenchEval : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(binary("softevo"))) GTEST_SKIP() << "softevo not built: " << binary("softevo");
    dir_ = test::fresh_test_dir("cmd_bench_eval");
    write_bench_robot(dir_ / "a-gait.robot.json", "a-gait", false);
    write_bench_robot(dir_ / "b-directed.robot.json", "b-directed", true);
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  fs::path dir_;
};

TEST_F(CmdBenchEval, BestOfRunsReportsTheGaitRobotAgainstItsReference) {
  const auto r =
      run_command(binary("softevo") + " bench eval '" + dir_.string() + "' --runs 2 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(j["runs"], 2);
  EXPECT_EQ(j["robots"], 1) << "the directed robot is not a gait champion";
  ASSERT_EQ(j["per_robot"].size(), 1u);
  const nlohmann::json& row = j["per_robot"][0];
  EXPECT_EQ(row["name"], "a-gait");
  EXPECT_EQ(row["status"], "ok") << "a killed robot's time says nothing about speed";
  EXPECT_EQ(row["reference_cpu_seconds"].get<double>(), kReferenceCpuSeconds);
  EXPECT_EQ(row["voxels"], 5 * 3 * 3 - 1);
  EXPECT_GT(row["steps"].get<long long>(), 0);
  const double cpu = row["cpu_seconds"].get<double>();
  ASSERT_GT(cpu, 0.0);
  EXPECT_DOUBLE_EQ(j["median_speedup"].get<double>(), kReferenceCpuSeconds / cpu);
  EXPECT_DOUBLE_EQ(j["median_cpu_seconds"].get<double>(), cpu);
}

// --baseline: the A/B of two builds (here this build against itself): per robot both CPU times
// and their ratio, the same fitness bits, --with adding the directed robot, and --csv appending
// one row per robot with the CPU and both commits.
TEST_F(CmdBenchEval, BaselineComparesTwoBuildsRobotByRobotAndRecordsCsvRows) {
  const fs::path csv = dir_ / "results.csv";
  const auto r = run_command(binary("softevo") + " bench eval '" + dir_.string() +
                             "' --baseline '" + binary("softevo") +
                             "' --with b-directed --runs 2 --json --csv '" + csv.string() + "'");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output.substr(r.output.find("{\n")));
  EXPECT_EQ(j["runs"], 2);
  ASSERT_EQ(j["per_robot"].size(), 2u) << "the gait robot and the directed robot of --with";
  EXPECT_EQ(j["per_robot"][0]["name"], "a-gait");
  EXPECT_EQ(j["per_robot"][1]["name"], "b-directed");
  for (const nlohmann::json& row : j["per_robot"]) {
    const double base = row["baseline_cpu_seconds"].get<double>();
    const double ours = row["cpu_seconds"].get<double>();
    ASSERT_GT(base, 0.0);
    ASSERT_GT(ours, 0.0);
    EXPECT_DOUBLE_EQ(row["speedup"].get<double>(), base / ours);
    EXPECT_EQ(row["status"], "ok");
  }
  EXPECT_EQ(j["baseline_commit"], j["commit"]);
  // two runs per build: how much each build's own runs differ, the noise to judge a speed-up by
  const double spread_median = j["run_spread_median"].get<double>();
  const double spread_max = j["run_spread_max"].get<double>();
  EXPECT_GE(spread_median, 0.0);
  EXPECT_GE(spread_max, spread_median);
  EXPECT_FALSE(j["cpu"].get<std::string>().empty());
  const std::string worst = j["worst_robot"];
  EXPECT_TRUE(worst == "a-gait" || worst == "b-directed") << worst;
  std::ifstream in(csv);
  std::string header, line;
  ASSERT_TRUE(std::getline(in, header));
  EXPECT_EQ(header.rfind("date_utc,cpu,simd,commit,baseline_commit,", 0), 0u) << header;
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    EXPECT_NE(line.find(rows == 1 ? ",a-gait," : ",b-directed,"), std::string::npos) << line;
  }
  EXPECT_EQ(rows, 2);
}

// --only narrows the gait robots; a file named by --with is taken whatever --only says.
TEST_F(CmdBenchEval, WithAddsItsRobotsBesideOnly) {
  const auto r = run_command(binary("softevo") + " bench eval '" + dir_.string() +
                             "' --only no-such-robot --with b-directed --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  ASSERT_EQ(j["per_robot"].size(), 1u) << r.output;
  EXPECT_EQ(j["per_robot"][0]["name"], "b-directed");
  const auto none =
      run_command(binary("softevo") + " bench eval '" + dir_.string() + "' --only no-such-robot");
  EXPECT_NE(none.code, 0) << "nothing selected: " << none.output;
}

TEST_F(CmdBenchEval, MissingBaselineIsAnError) {
  const auto r = run_command(binary("softevo") + " bench eval '" + dir_.string() +
                             "' --baseline '" + (dir_ / "no-such-softevo").string() + "'");
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("no-such-softevo"), std::string::npos) << r.output;
}

TEST_F(CmdBenchEval, RunCountOutOfRangeIsAUsageError) {
  const auto r = run_command(binary("softevo") + " bench eval '" + dir_.string() + "' --runs 0");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--runs"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace softevo
