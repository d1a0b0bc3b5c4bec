// Faults under MPI (issue 21 item 9), with the real launcher: softevo-mpi under `mpirun -np 3`
// (or as an isolated MPI singleton, which starts in a fraction of the time) on a tiny problem.
// Each case injects the fault from outside - SIGKILL of one worker rank, SIGTERM to mpirun
// while the workers are inside long evaluations, SIGKILL of mpirun's whole process group,
// SIGKILL at random instants - and checks what the user is told, the archive's state, and that
// a --resume ends with the digests of an uninterrupted run.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/config.hpp"
#include "io/archive.hpp"
#include "io/run_lock.hpp"
#include "master/run_state.hpp"
#include "tests/build_tree.hpp"
#include "tests/master/child_process.hpp"

#ifndef SOFTEVO_MPIEXEC
#define SOFTEVO_MPIEXEC "mpirun"
#endif

namespace softevo {
namespace {

namespace fs = std::filesystem;
using test::file_bytes;
using test::wait_exit;
using test::wait_until;

// The workers' evaluations take seconds of wall time each with `eval_seconds` = 6 (more than
// mpirun's 1 s between SIGTERM and SIGKILL), a few milliseconds with 0.1.
std::string tiny_config(double eval_seconds, int pop_size) {
  return "[run]\nseed = 7\n[task]\nkind = \"gait\"\ncontrol = \"open\"\neval_seconds = " +
         std::to_string(eval_seconds) +
         "\n[body]\nlattice = [5, 5, 5]\n[neat]\npop_size = " + std::to_string(pop_size) + "\n";
}

struct Snapshot {
  std::string state;
  std::int64_t generations_done = -1;
  std::string fitness, content;
};
// The archive at `path` now; nothing if it does not exist (yet) or cannot be read.
std::optional<Snapshot> snapshot(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  try {
    const io::Archive a(path);
    return Snapshot{to_string(a.info().state), a.info().generations_done,
                    hash_hex(fitness_digest(a)), hash_hex(content_digest(a))};
  } catch (const io::ArchiveError&) {
    return std::nullopt;
  }
}

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

class SoftevoMpiFaults : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::fresh_test_dir("mpi_faults"); }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  std::string write_config(const std::string& text) const {
    const std::string path = file("run.toml");
    std::ofstream(path) << text;
    return path;
  }

  // softevo-mpi as an isolated singleton (no orted: starts in well under a second).
  static pid_t start_alone(const std::vector<std::string>& args, const std::string& log) {
    std::vector<std::string> argv = {test::binary("softevo-mpi")};
    argv.insert(argv.end(), args.begin(), args.end());
    return test::spawn_child(argv, log, {{"OMPI_MCA_ess_singleton_isolated=1"}, false});
  }
  static pid_t start_mpirun(int ranks, const std::vector<std::string>& args, const std::string& log,
                            bool own_process_group = false) {
    std::vector<std::string> argv = {SOFTEVO_MPIEXEC, "-np", std::to_string(ranks),
                                     test::binary("softevo-mpi")};
    argv.insert(argv.end(), args.begin(), args.end());
    return test::spawn_child(argv, log, {{}, own_process_group});
  }
  // Runs softevo-mpi alone to its end; its exit code.
  int run_alone(const std::vector<std::string>& args, const std::string& log) const {
    const pid_t child = start_alone(args, file(log));
    return child > 0 ? wait_exit(child) : -1;
  }
  // The uninterrupted run of `common` (into ref.h5); nothing (and a failure) if it fails.
  std::optional<Snapshot> reference(const std::vector<std::string>& common) const {
    if (run_alone(with(common, {"--out", file("ref.h5")}), "ref.log") == 0)
      return snapshot(file("ref.h5"));
    ADD_FAILURE() << file_bytes(file("ref.log"));
    return std::nullopt;
  }
  // Waits (at most 120 s) until `out` holds its first generation.
  static bool first_generation_archived(const std::string& out) {
    return wait_until(
        [&out] {
          const std::optional<Snapshot> s = snapshot(out);
          return s && s->generations_done >= 1;
        },
        120);
  }
  // --resume of `args` alone must complete with the digests of `expected`; the resume's log.
  std::string expect_resume_to(const std::vector<std::string>& args,
                               const Snapshot& expected) const {
    EXPECT_EQ(run_alone(with(args, {"--resume"}), "resume.log"), 0);
    const std::string log = file_bytes(file("resume.log"));
    const std::optional<Snapshot> resumed = snapshot(args.back());
    EXPECT_TRUE(resumed.has_value()) << log;
    if (resumed) {
      EXPECT_EQ(resumed->state, "complete") << log;
      EXPECT_EQ(resumed->fitness, expected.fitness);
      EXPECT_EQ(resumed->content, expected.content);
    }
    return log;
  }

  fs::path dir_;
};

// The pid in the run lock of `archive` ("pid 4242 on node17"): rank 0's process.
long master_pid(const std::string& archive) {
  const std::string text = file_bytes(io::lock_path_for(archive));
  return text.rfind("pid ", 0) == 0 ? std::atol(text.c_str() + 4) : -1;
}

// The softevo-mpi processes whose parent is `parent` (mpirun's ranks).
std::vector<long> rank_processes(pid_t parent) {
  std::vector<long> pids;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = file_bytes(entry.path().string() + "/stat");
    const std::size_t open = stat.find('('), close = stat.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    long ppid = 0;
    char state = 0;
    if (std::sscanf(stat.c_str() + close + 2, "%c %ld", &state, &ppid) != 2) continue;
    if (ppid == parent && stat.substr(open + 1, close - open - 1) == "softevo-mpi")
      pids.push_back(std::atol(name.c_str()));
  }
  return pids;
}

bool process_alive(long pid) {
  const std::string stat = file_bytes("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] != 'Z';
}

bool all_ended(const std::vector<long>& pids) {
  for (long pid : pids)
    if (process_alive(pid)) return false;
  return true;
}

TEST_F(SoftevoMpiFaults, AKilledWorkerRankIsNamedAndTheArchiveResumesToTheSameDigests) {
  const std::vector<std::string> common = {"--config", write_config(tiny_config(0.1, 6)),
                                           "--generations", "8"};
  const std::optional<Snapshot> expected = reference(common);
  ASSERT_TRUE(expected.has_value());

  const std::string out = file("killed.h5"), log = file("killed.log");
  const std::vector<std::string> args = with(common, {"--out", out});
  const pid_t mpirun = start_mpirun(3, args, log);
  ASSERT_GT(mpirun, 0);
  ASSERT_TRUE(first_generation_archived(out)) << file_bytes(log);
  const long master = master_pid(out);
  long victim = -1;
  for (long pid : rank_processes(mpirun))
    if (pid != master) victim = pid;
  ASSERT_GT(victim, 0) << "no worker rank found";
  kill(static_cast<pid_t>(victim), SIGKILL);
  EXPECT_NE(wait_exit(mpirun), 0);

  // The master survived mpirun's SIGTERM long enough: one line naming the rank and where
  // --resume continues, and the state says so.
  const std::string text = file_bytes(log);
  EXPECT_NE(text.find("was lost (its process, pid " + std::to_string(victim) + ", is gone"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("--resume continues from generation"), std::string::npos) << text;
  const Snapshot killed = *snapshot(out);
  EXPECT_EQ(killed.state, "interrupted") << text;
  EXPECT_LT(killed.generations_done, 8);

  const std::string resumed = expect_resume_to(args, *expected);
  EXPECT_NE(resumed.find("the previous run on this archive was interrupted (it stopped after a "
                         "signal or an error, see its log) at generation " +
                         std::to_string(killed.generations_done)),
            std::string::npos)
      << resumed;
}

TEST_F(SoftevoMpiFaults, SigtermDuringLongEvaluationsCheckpointsTellsAndResumes) {
  const std::vector<std::string> common = {"--config", write_config(tiny_config(30.0, 2)),
                                           "--generations", "2"};
  const std::optional<Snapshot> expected = reference(common);
  ASSERT_TRUE(expected.has_value());

  const std::string out = file("term.h5"), log = file("term.log");
  const std::vector<std::string> args = with(common, {"--out", out});
  const pid_t mpirun = start_mpirun(3, args, log);
  ASSERT_GT(mpirun, 0);
  ASSERT_TRUE(first_generation_archived(out)) << file_bytes(log);
  // Generation 1's two evaluations have just been handed out: each takes seconds (30 s of
  // simulated time; 6 s took only a few hundred ms on an idle machine, too short to be caught).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const std::vector<long> ranks = rank_processes(mpirun);
  EXPECT_EQ(ranks.size(), 3u);
  kill(mpirun, SIGTERM);
  wait_exit(mpirun);  // mpirun itself reports 1 (it was signalled)
  EXPECT_TRUE(wait_until([&] { return all_ended(ranks); }, 10)) << "a rank outlived mpirun";

  const std::string text = file_bytes(log);
  EXPECT_NE(text.find("softevo-mpi: stopping at once: rank 0 received SIGTERM; generation 1 is "
                      "dropped, the archive keeps generations 0-0 and --resume continues from "
                      "generation 1"),
            std::string::npos)
      << text;
  const Snapshot stopped = *snapshot(out);
  EXPECT_EQ(stopped.state, "interrupted") << text;
  EXPECT_EQ(stopped.generations_done, 1);
  expect_resume_to(args, *expected);
}

TEST_F(SoftevoMpiFaults, OrphanedRanksStopWhenMpirunsProcessGroupIsKilled) {
  const std::string out = file("orphan.h5"), log = file("orphan.log");
  const pid_t mpirun = start_mpirun(
      3, {"--config", write_config(tiny_config(0.1, 6)), "--generations", "200", "--out", out}, log,
      true);
  ASSERT_GT(mpirun, 0);
  ASSERT_TRUE(first_generation_archived(out)) << file_bytes(log);
  const std::vector<long> ranks = rank_processes(mpirun);
  EXPECT_EQ(ranks.size(), 3u);
  const std::int64_t before = snapshot(out)->generations_done;
  kill(-mpirun, SIGKILL);  // mpirun's group; the ranks lead groups of their own and live on
  wait_exit(mpirun);
  EXPECT_TRUE(wait_until([&] { return all_ended(ranks); }, 20)) << "orphaned ranks kept running";
  const Snapshot after = *snapshot(out);
  // At most the generation in flight was still archived; then the master marked the archive.
  EXPECT_LE(after.generations_done, before + 1);
  EXPECT_EQ(after.state, "interrupted");
  EXPECT_FALSE(io::lock_holder(out).has_value()) << "the lock outlived the run";
}

// SIGKILL (no chance to clean up) of a run at random instants, start-up and archive writes
// included: every killed archive is absent (killed before its creation) or valid, `info` and the
// next start say what happened, and --resume ends with the digests of an uninterrupted run.
TEST_F(SoftevoMpiFaults, SigkillAtRandomInstantsTwentyTimesResumesToTheSameDigests) {
  const std::vector<std::string> common = {"--config", write_config(tiny_config(0.1, 6)),
                                           "--generations", "6"};
  const auto t0 = std::chrono::steady_clock::now();
  const std::optional<Snapshot> expected = reference(common);
  ASSERT_TRUE(expected.has_value());
  const double run_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::mt19937_64 rng(20261201);  // fixed: a failure names an instant that can be rerun
  std::uniform_real_distribution<double> instant(0.0, run_seconds);
  int interrupted_runs = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const double at = instant(rng);
    SCOPED_TRACE("trial " + std::to_string(trial) + ": SIGKILL after " + std::to_string(at) + " s");
    const std::string out = file("trial" + std::to_string(trial) + ".h5");
    const std::vector<std::string> args = with(common, {"--out", out});
    const pid_t child = start_alone(args, file("trial.log"));
    ASSERT_GT(child, 0);
    std::this_thread::sleep_for(std::chrono::duration<double>(at));
    kill(child, SIGKILL);
    wait_exit(child);
    const std::optional<Snapshot> killed = snapshot(out);
    std::error_code ec;
    EXPECT_TRUE(killed.has_value() || !fs::exists(out, ec)) << "unreadable archive left";
    const bool died_running = killed && killed->state == "running";
    if (died_running) {
      ++interrupted_runs;
      const std::optional<std::string> note =
          master::previous_run_note(io::Archive(out).info(), io::lock_holder(out));
      ASSERT_TRUE(note.has_value());
      EXPECT_NE(note->find("its process died without closing"), std::string::npos) << *note;
      if (interrupted_runs == 1) {  // the command itself says it too
        const test::CommandResult shown =
            test::run_command(test::binary("softevo") + " info " + out);
        EXPECT_NE(shown.output.find("state            running, " +
                                    std::to_string(killed->generations_done) +
                                    " generations done\n                 the previous run on "
                                    "this archive was interrupted (its process died"),
                  std::string::npos)
            << shown.output;
      }
    }
    const std::string resumed = expect_resume_to(args, *expected);
    if (died_running) {  // killed after the last generation: only the closing was missing
      EXPECT_NE(resumed.find(killed->generations_done == 6
                                 ? std::string("--resume marks it complete")
                                 : "--resume continues from generation " +
                                       std::to_string(killed->generations_done)),
                std::string::npos)
          << resumed;
    }
  }
  // The instants spread over the run: most kills hit it while it was running.
  EXPECT_GE(interrupted_runs, 5);
}

}  // namespace
}  // namespace softevo
