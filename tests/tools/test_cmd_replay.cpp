// `softevo replay --verify` end to end: a fresh tiny run of the real `softevo-mpi` (one rank)
// is replayed bit for bit; the same archive with one fitness value nudged by one ulp, or with
// a foreign config hash, must fail.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "io/h5.hpp"
#include "tests/build_tree.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;

using test::binary;
using Result = test::CommandResult;

Result run(const std::string& command) {
  return test::run_command(command);
}

class CmdReplay : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(binary("softevo")) || !fs::exists(binary("softevo-mpi"))) return;
    if (!fs::exists("configs/quickstart.toml")) return;
    dir_ = fs::temp_directory_path() / ("softevo_test_cmd_replay_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    archive_ = (dir_ / "run.h5").string();
    // Tiny but real: 6 genomes of up to 4x4x4 voxels, 2 generations, 1 s of simulated time.
    run_result_ = run(binary("softevo-mpi") +
                      " --config configs/quickstart.toml --seed 3 --generations 2 --population 6 "
                      "--set body.lattice=[4,4,4] "
                      "--set task.eval_seconds=1.0 --out " +
                      archive_);
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  void SetUp() override {
    if (archive_.empty()) {
      GTEST_SKIP() << "softevo, softevo-mpi or configs/quickstart.toml missing (build both)";
    }
    ASSERT_EQ(run_result_.code, 0) << run_result_.output;
  }
  // A copy of the archive with one change made through `edit`.
  static std::string tampered_copy(const std::string& name,
                                   const std::function<void(const io::h5::File&)>& edit) {
    const std::string path = (dir_ / name).string();
    fs::copy_file(archive_, path, fs::copy_options::overwrite_existing);
    const io::h5::File file = io::h5::File::open(path, io::h5::File::Access::read_write);
    edit(file);
    return path;
  }
  static fs::path dir_;
  static std::string archive_;
  static Result run_result_;
};

fs::path CmdReplay::dir_;
std::string CmdReplay::archive_;
Result CmdReplay::run_result_;

TEST_F(CmdReplay, VerifyAllPassesOnAFreshRun) {
  for (const char* gen : {"0", "1"}) {
    const Result r =
        run(binary("softevo") + " replay " + archive_ + " --all --verify --generation " + gen);
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("0 mismatched"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("MISMATCH"), std::string::npos) << r.output;
  }
  const Result best = run(binary("softevo") + " replay " + archive_ + " --best --verify");
  EXPECT_EQ(best.code, 0) << best.output;
  EXPECT_NE(best.output.find("IDENTICAL"), std::string::npos) << best.output;
}

TEST_F(CmdReplay, OneUlpOfTamperedFitnessIsAMismatch) {
  const std::string path = tampered_copy("fitness.h5", [](const io::h5::File& file) {
    const io::h5::Dataset ds = file.open_dataset("generations/000001/fitness");
    std::vector<double> f = ds.read<double>();
    f.back() = std::nextafter(f.back(), INFINITY);  // smallest possible change
    ds.write(f);
  });
  const Result r = run(binary("softevo") + " replay " + path + " --all --verify --generation 1");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("MISMATCH"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 mismatched"), std::string::npos) << r.output;
  // Without --verify the replay itself still works and reports the fitness.
  EXPECT_EQ(run(binary("softevo") + " replay " + path + " --generation 1").code, 0);
}

TEST_F(CmdReplay, TamperedStatusIsAMismatch) {
  const std::string path = tampered_copy("status.h5", [](const io::h5::File& file) {
    const io::h5::Dataset ds = file.open_dataset("generations/000000/status");
    std::vector<std::uint8_t> s = ds.read<std::uint8_t>();
    s[0] = s[0] == 1 ? 2 : 1;  // a killed status the robot did not have
    ds.write(s);
  });
  const Result r = run(binary("softevo") + " replay " + path + " --all --verify --generation 0");
  EXPECT_EQ(r.code, 1) << r.output;
}

TEST_F(CmdReplay, ForeignConfigHashIsRefused) {
  const std::string path = tampered_copy("hash.h5", [](const io::h5::File& file) {
    file.write_string_attribute("config_hash", "0000000000000000", io::h5::Charset::utf8);
  });
  const Result r = run(binary("softevo") + " replay " + path + " --verify");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("config_hash"), std::string::npos) << r.output;
}

// Bits are only comparable within one physics revision (physics/revision.hpp): --verify of an
// archive of another revision is refused with both revisions named; a plain replay still runs.
TEST_F(CmdReplay, OtherPhysicsRevisionIsRefusedByVerify) {
  const std::string path = tampered_copy("revision.h5", [](const io::h5::File& file) {
    file.write_attribute<std::int32_t>("physics_revision", 1);
  });
  const Result r = run(binary("softevo") + " replay " + path + " --best --verify");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("physics revision 1"), std::string::npos) << r.output;
  const Result plain = run(binary("softevo") + " replay " + path + " --best");
  EXPECT_EQ(plain.code, 0) << plain.output;
  EXPECT_NE(plain.output.find("physics revision 1"), std::string::npos) << plain.output;
}

TEST_F(CmdReplay, UnknownIdOrGenerationIsAUsageError) {
  Result r = run(binary("softevo") + " replay " + archive_ + " --id 999999");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("999999"), std::string::npos) << r.output;
  r = run(binary("softevo") + " replay " + archive_ + " --generation 7");
  EXPECT_EQ(r.code, 2) << r.output;
}

}  // namespace
}  // namespace softevo
