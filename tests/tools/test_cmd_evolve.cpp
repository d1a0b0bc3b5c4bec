// `softevo evolve` end to end against softevo-mpi, with the real evaluator on tiny problems
// (5x5x5 lattice, 0.1 s robots): any number of worker threads writes the archive softevo-mpi
// writes at np = 1 and (with mpirun) np = 3, for the gait and the directed task (fitness and
// content digests); a SIGKILL followed by --resume, and SIGTERM/SIGUSR1 (exit 75, state
// interrupted) followed by --resume, give the archive of an uninterrupted run; start-up errors
// exit 2 and touch nothing.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "io/archive.hpp"
#include "tests/build_tree.hpp"
#include "tests/master/child_process.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;
using test::binary;

// The tiny real problem shared with tests/python/test_evolve.py.
std::string tiny_config() {
  const char* source = std::getenv("SOFTEVO_SOURCE_DIR");
  return std::string(source != nullptr ? source : ".") + "/tests/data/tiny-run.toml";
}

struct Digests {
  std::string fitness, content, state;
  std::int64_t generations_done = -1;
  int ranks = 0;
};
Digests digests(const std::string& path) {
  const io::Archive a(path);
  return {hash_hex(io::fitness_digest(a)), hash_hex(io::content_digest(a)),
          to_string(a.info().state), a.info().generations_done, a.info().ranks};
}

std::string join(const std::vector<std::string>& args) {
  std::string s;
  for (const std::string& a : args) s += " '" + a + "'";
  return s;
}

class CmdEvolve : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(binary("softevo")) || !fs::exists(binary("softevo-mpi")))
      GTEST_SKIP() << "softevo or softevo-mpi not built";
    config_ = tiny_config();
    if (!fs::exists(config_)) GTEST_SKIP() << config_ << " not found";
    dir_ = test::fresh_test_dir("cmd_evolve");
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  test::CommandResult evolve(const std::vector<std::string>& args) const {
    return test::run_command(binary("softevo") + " evolve --progress never" + join(args));
  }
  test::CommandResult mpi(int np, const std::vector<std::string>& args) const {
    std::string launcher;
#ifdef SOFTEVO_MPIEXEC
    if (np > 1)
      launcher = std::string(SOFTEVO_MPIEXEC) + " --oversubscribe -np " + std::to_string(np) + " ";
#endif
    if (np > 1 && launcher.empty()) return {};
    return test::run_command("env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " +
                             launcher + binary("softevo-mpi") + " --progress never" + join(args));
  }
  fs::path dir_;
  std::string config_;
};

TEST_F(CmdEvolve, WritesTheArchiveOfSoftevoMpiAtAnyRankCount) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> problems = {
      {"gait", {}},
      {"directed",
       {"--set", "task.kind=directed", "--set", "task.eval_seconds=0.05", "--generations", "2",
        "--population", "4"}}};
  for (const auto& [kind, extra] : problems) {
    std::vector<std::string> common = {"--config", config_};
    common.insert(common.end(), extra.begin(), extra.end());
    const auto with_out = [&](const std::string& out) {
      std::vector<std::string> a = common;
      a.insert(a.end(), {"--out", out});
      return a;
    };
    const std::string np1 = file(kind + "-np1.h5");
    const test::CommandResult r1 = mpi(1, with_out(np1));
    ASSERT_EQ(r1.code, 0) << r1.output;
    const Digests reference = digests(np1);
    std::vector<std::string> compared = {np1};
    const std::string np3 = file(kind + "-np3.h5");
    const test::CommandResult r3 = mpi(3, with_out(np3));
    if (r3.code != -1 || !r3.output.empty()) {
      ASSERT_EQ(r3.code, 0) << r3.output;
      compared.push_back(np3);
    }
    for (int workers : {1, 3}) {
      const std::string out = file(kind + "-w" + std::to_string(workers) + ".h5");
      std::vector<std::string> args = with_out(out);
      args.insert(args.end(), {"--workers", std::to_string(workers)});
      const test::CommandResult r = evolve(args);
      ASSERT_EQ(r.code, 0) << r.output;
      EXPECT_NE(r.output.find(std::to_string(workers) + " worker thread"), std::string::npos)
          << r.output;
      EXPECT_NE(r.output.find("# complete"), std::string::npos) << r.output;
      compared.push_back(out);
      EXPECT_EQ(digests(out).ranks, workers + 1);
    }
    for (const std::string& path : compared) {
      const Digests d = digests(path);
      EXPECT_EQ(d.fitness, reference.fitness) << path;
      EXPECT_EQ(d.content, reference.content) << path;
      EXPECT_EQ(d.state, "complete") << path;
    }
  }
}

// Waits (max 120 s) until the archive has at least `g` generations; false if the child ended.
bool wait_for_generations(const std::string& path, std::int64_t g, pid_t child) {
  return test::wait_until(
             [&] {
               int st = 0;
               if (waitpid(child, &st, WNOHANG) == child) return true;
               std::error_code ec;
               if (!fs::exists(path, ec)) return false;
               try {
                 return io::Archive(path).info().generations_done >= g;
               } catch (const io::ArchiveError&) {
                 return false;
               }
             },
             120) &&
         fs::exists(path) && io::Archive(path).info().generations_done >= g;
}

TEST_F(CmdEvolve, ResumeAfterSigkillOrAStopSignalGivesTheSameArchive) {
  const std::vector<std::string> common = {"--config", config_,     "--generations",
                                           "6",        "--workers", "2"};
  std::vector<std::string> ref_args = common;
  ref_args.insert(ref_args.end(), {"--out", file("ref.h5")});
  const test::CommandResult ref = evolve(ref_args);
  ASSERT_EQ(ref.code, 0) << ref.output;
  const Digests expected = digests(file("ref.h5"));
  for (int sig : {SIGKILL, SIGTERM, SIGINT, SIGUSR1}) {
    const std::string out = file("sig" + std::to_string(sig) + ".h5");
    std::vector<std::string> argv = {binary("softevo"), "evolve", "--progress", "never"};
    argv.insert(argv.end(), common.begin(), common.end());
    argv.insert(argv.end(), {"--out", out});
    const pid_t child = test::spawn_child(argv, file("child.log"));
    ASSERT_GT(child, 0);
    ASSERT_TRUE(wait_for_generations(out, 2, child)) << test::file_bytes(file("child.log"));
    kill(child, sig);
    bool signalled = false;
    const int code = test::wait_exit(child, &signalled);
    const Digests stopped = digests(out);
    if (sig == SIGKILL) {
      EXPECT_TRUE(signalled) << "the child finished before it could be killed";
      EXPECT_EQ(stopped.state, "running");
    } else {
      EXPECT_EQ(code, 75) << test::file_bytes(file("child.log"));
      EXPECT_EQ(stopped.state, "interrupted");
      EXPECT_NE(test::file_bytes(file("child.log")).find("--resume"), std::string::npos);
    }
    EXPECT_LT(stopped.generations_done, 6) << "signal " << sig;
    std::vector<std::string> resume = common;
    resume.insert(resume.end(), {"--out", out, "--resume"});
    const test::CommandResult r = evolve(resume);
    ASSERT_EQ(r.code, 0) << r.output;
    const Digests d = digests(out);
    EXPECT_EQ(d.state, "complete");
    EXPECT_EQ(d.fitness, expected.fitness) << "signal " << sig;
    EXPECT_EQ(d.content, expected.content) << "signal " << sig;
  }
}

TEST_F(CmdEvolve, StartupErrorsExitTwoAndTouchNothing) {
  const test::CommandResult missing = evolve({"--config", file("absent.toml")});
  EXPECT_EQ(missing.code, 2) << missing.output;
  EXPECT_NE(missing.output.find("absent.toml"), std::string::npos) << missing.output;
  const std::string out = file("run.h5");
  ASSERT_EQ(evolve({"--config", config_, "--out", out, "--generations", "1"}).code, 0);
  const std::string before = test::file_bytes(out);
  const test::CommandResult again = evolve({"--config", config_, "--out", out});
  EXPECT_EQ(again.code, 2) << again.output;
  EXPECT_NE(again.output.find("--resume"), std::string::npos) << again.output;
  EXPECT_EQ(test::file_bytes(out), before);
  const test::CommandResult workers = evolve({"--config", config_, "--workers", "0"});
  EXPECT_EQ(workers.code, 2) << workers.output;
  const test::CommandResult help = test::run_command(binary("softevo") + " --help");
  EXPECT_NE(help.output.find("evolve"), std::string::npos) << help.output;
}

// --resume of an archive that does not exist, without --config, is an error naming the path and
// the archives beside it (issue 39: a mistyped `--out runs/gait-open-3.h5 --resume` silently
// ran the default config); with --config it starts the run (the Slurm scripts rely on it).
TEST_F(CmdEvolve, ResumeOfAMissingArchiveIsAnErrorWithoutAConfig) {
  const std::string real = file("gait-open-03.h5");
  ASSERT_EQ(evolve({"--config", config_, "--out", real, "--generations", "1"}).code, 0);
  const std::string typo = file("gait-open-3.h5");
  const test::CommandResult r = evolve({"--out", typo, "--resume"});
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(typo + ": cannot resume: no such archive; archives near it: " + real),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(typo));
  const test::CommandResult mpi_run = mpi(1, {"--out", typo, "--resume"});
  EXPECT_EQ(mpi_run.code, 2) << mpi_run.output;
  EXPECT_NE(mpi_run.output.find("no such archive"), std::string::npos) << mpi_run.output;
  const test::CommandResult no_out = evolve({"--resume"});
  EXPECT_EQ(no_out.code, 2) << no_out.output;
  EXPECT_NE(no_out.output.find("--resume without --config continues the archive that --out names"),
            std::string::npos)
      << no_out.output;
  EXPECT_FALSE(fs::exists(typo));
  // With --config, --resume starts a run whose archive is absent.
  const std::string fresh = file("fresh.h5");
  const test::CommandResult start =
      evolve({"--config", config_, "--out", fresh, "--generations", "1", "--resume"});
  EXPECT_EQ(start.code, 0) << start.output;
  EXPECT_TRUE(fs::exists(fresh));
}

// --resume without --config takes the archive's own config; an override of its search strategy
// is refused naming both strategies (before, the first map_elites key of the archive's config
// failed as "applies only when ...", not saying that a run keeps its strategy).
TEST_F(CmdEvolve, ResumeWithAnotherStrategyOverrideNamesBoth) {
  const std::string out = file("map.h5");
  const std::vector<std::string> map_elites = {
      "--config",      config_,
      "--out",         out,
      "--generations", "1",
      "--set",         "search.strategy=\"map_elites\"",
      "--set",         "map_elites.descriptors=[\"voxels\"]",
      "--set",         "map_elites.min=[0]",
      "--set",         "map_elites.max=[125]",
      "--set",         "map_elites.bins=[5]"};
  const test::CommandResult start = evolve(map_elites);
  ASSERT_EQ(start.code, 0) << start.output;
  for (const std::string value : {"afpo", "\"afpo\"", "'neat'"}) {
    const test::CommandResult r = evolve(
        {"--out", out, "--resume", "--generations", "2", "--set", "search.strategy=" + value});
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(out + ": cannot resume: the archive was evolved by search strategy "
                                  "\"map_elites\", this run asks for "),
              std::string::npos)
        << r.output;
  }
  EXPECT_EQ(io::Archive(out).info().generations_done, 1);
  // Naming the archive's own strategy is no change.
  const test::CommandResult same = evolve(
      {"--out", out, "--resume", "--generations", "2", "--set", "search.strategy=map_elites"});
  EXPECT_EQ(same.code, 0) << same.output;
  EXPECT_EQ(io::Archive(out).info().generations_done, 2);
}

// A run in which no robot is ever ok (every one diverged or exploded) is archived complete but
// ends with exit 1, as one stopped by failed generations does (issue 39: it exited 0); the
// warnings of `softevo evolve` carry its own name.
TEST_F(CmdEvolve, ARunWithoutARobotOkExitsOne) {
  const std::vector<std::string> args = {"--config", config_,
                                         "--set",    "pneumatics.conductivity=15",
                                         "--set",    "run.stop_after_failed_generations=0"};
  std::vector<std::string> threaded = args;
  threaded.insert(threaded.end(), {"--out", file("threads.h5")});
  const test::CommandResult r = evolve(threaded);
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("softevo evolve: error: " + file("threads.h5") +
                          ": no robot of the 18 evaluated was ok (ok 0,"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("softevo evolve: warning: generation 0: all 6 robots were killed"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("softevo-mpi:"), std::string::npos) << r.output;
  EXPECT_EQ(digests(file("threads.h5")).state, "complete");
  std::vector<std::string> ranks = args;
  ranks.insert(ranks.end(), {"--out", file("mpi.h5")});
  const test::CommandResult m = mpi(1, ranks);
  EXPECT_EQ(m.code, 1) << m.output;
  EXPECT_NE(m.output.find("softevo-mpi: error: " + file("mpi.h5") + ": no robot"),
            std::string::npos)
      << m.output;
}

// A real full disk (a 200 kB tmpfs, full after the first generation; root only, else skipped):
// the run ends with exit 1 and the cause, never a signal, and the archive resumes once there is
// room (issue 39: 7 of 14 trials ended with SIGSEGV in libhdf5's clean-up at exit, after the
// right message, because the id of the file whose close failed stayed registered).
TEST_F(CmdEvolve, AFullDiskEndsWithExitOneNotASignal) {
  const std::string small = file("small");
  fs::create_directory(small);
  const std::string out = small + "/run.h5";
  for (int trial = 0; trial < 3; ++trial) {
    if (::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=200k") != 0)
      GTEST_SKIP() << "cannot mount a small tmpfs (" << std::strerror(errno) << "; needs root)";
    const test::CommandResult r = evolve({"--config", config_, "--out", out, "--generations", "6"});
    EXPECT_EQ(r.code, 1) << "trial " << trial << ": " << r.output;
    EXPECT_NE(r.output.find("No space left on device"), std::string::npos) << r.output;
    if (trial == 2) {
      EXPECT_EQ(::mount("tmpfs", small.c_str(), "tmpfs", MS_REMOUNT, "size=8m"), 0)
          << std::strerror(errno);
      const test::CommandResult resumed = evolve({"--out", out, "--resume"});
      EXPECT_EQ(resumed.code, 0) << resumed.output;
      EXPECT_EQ(digests(out).state, "complete");
    }
    ::umount2(small.c_str(), MNT_DETACH);
  }
}

// A --seeds job that cannot hold a lock descriptor per run is refused before it takes any,
// naming the limit and the number needed; the soft limit is raised when the hard one suffices;
// a job that fails while preparing its runs leaves no lock file and no folder it created
// (issue 29: 1,100 seeds under ulimit -n 1024 said "cannot open config file" and left 1,004
// lock files).
TEST_F(CmdEvolve, PackedStartChecksDescriptorsAndLeavesNothingOnFailure) {
  const std::string dir = file("many");
  // `softevo evolve --seeds SEEDS` into `dir` under the shell's descriptor limits `limits`.
  const auto evolve_limited = [&](const std::string& limits, const std::string& seeds) {
    return test::run_command(limits + " && exec " + binary("softevo") +
                             " evolve --progress never --workers 1 --generations 1" +
                             join({"--config", config_, "--seeds", seeds, "--out-dir", dir}));
  };
  const test::CommandResult tight = evolve_limited("ulimit -Sn 60 && ulimit -Hn 60", "1-200");
  EXPECT_EQ(tight.code, 2) << tight.output;
  EXPECT_NE(tight.output.find("file descriptors"), std::string::npos) << tight.output;
  EXPECT_NE(tight.output.find("the limit is 60"), std::string::npos) << tight.output;
  EXPECT_FALSE(fs::exists(dir)) << tight.output;

  // Soft limit 40, hard limit enough: the job raises its own soft limit and gets to the runs;
  // the third archive exists (no --resume) and stops the start: no lock file is left.
  fs::create_directories(dir);
  const std::string stem = fs::path(config_).stem().string();
  ASSERT_EQ(evolve({"--config", config_, "--out", (fs::path(dir) / (stem + "-03.h5")).string(),
                    "--generations", "1"})
                .code,
            0);
  EXPECT_FALSE(fs::exists(fs::path(dir) / (stem + "-03.h5.lock"))) << "left by a clean end";
  const test::CommandResult raised = evolve_limited("ulimit -Sn 40", "1-3");
  EXPECT_EQ(raised.code, 2) << raised.output;
  EXPECT_NE(raised.output.find("--resume"), std::string::npos) << raised.output;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{stem + "-03.h5"});
}

// Issue 30: `--progress auto` under mpirun whose output goes to a file (`nohup mpirun ... >
// log 2>&1`) writes no carriage return or ESC sequence: the ranks' stderr is a pipe to mpirun,
// which is judged by where mpirun sends it. And `info` gives its table's units.
TEST_F(CmdEvolve, NoControlSequencesInALogAndUnitsInInfo) {
#ifndef SOFTEVO_MPIEXEC
  GTEST_SKIP() << "no mpirun";
#else
  const std::string out = file("run.h5");
  const std::string log = file("log");
  const std::string command = "env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " +
                              std::string(SOFTEVO_MPIEXEC) + " --oversubscribe -np 2 " +
                              binary("softevo-mpi") + " --progress auto --config '" + config_ +
                              "' --out '" + out + "' --generations 2 > '" + log + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << test::file_bytes(log);
  const std::string text = test::file_bytes(log);
  EXPECT_NE(text.find("gen      1/2"), std::string::npos) << text;
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
  EXPECT_EQ(text.find('\033'), std::string::npos) << text;
  const test::CommandResult info = test::run_command(binary("softevo") + " info '" + out + "'");
  EXPECT_NE(info.output.find("best [cm]      mean [cm]        sd [cm]"), std::string::npos)
      << info.output;
  EXPECT_NE(info.output.find(" cm, status ok"), std::string::npos) << info.output;
  const test::CommandResult robot = test::run_command(binary("softevo") + " eval '" + out + "'");
  EXPECT_EQ(robot.code, 2) << robot.output;
  EXPECT_NE(robot.output.find("not a robot file: it is an HDF5 file"), std::string::npos)
      << robot.output;
#endif
}

// A job whose estimated memory exceeds the machine's is refused before anything is allocated
// or written, naming the keys to lower (10^6 members x 100 runs: about a terabyte).
TEST_F(CmdEvolve, JobBeyondTheMachinesMemoryIsRefused) {
  const std::string dir = file("huge");
  const test::CommandResult r = evolve(
      {"--config", config_, "--population", "1000000", "--seeds", "1-100", "--out-dir", dir});
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("of memory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("neat.pop_size"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir)) << r.output;
}

}  // namespace
}  // namespace softevo
