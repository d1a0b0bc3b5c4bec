// `softevo export` end to end on a tiny real run: the robot file is written atomically, an
// existing output is replaced only with --force, and symlinks or special files are refused with
// the target left as it was (docs/output-files.md).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/build_tree.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;
using test::binary;

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
                             "--population 4 --set body.lattice=[4,4,4] "
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

}  // namespace
}  // namespace softevo
