// The run loop's archive discipline (master/run.hpp) without MPI: a write that fails at any
// step of a generation's update leaves an archive that --resume continues to the same result,
// and a second run on the same archive is refused while the first holds its lock. The evaluator
// is a stand-in (fitness from the genome bytes), so each run takes milliseconds.
#include "master/run.hpp"

#include "master/signals.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"

namespace softevo::master {
namespace {

using io::Archive;

// Every file below `dir` (the segment directory included).
std::vector<std::string> files_below(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    names.push_back(std::filesystem::relative(e.path(), dir).string());
  return names;
}

// No temporary and no segment directory is left below `dir`: every archive there is one file.
void expect_no_debris(const std::string& dir) {
  for (const std::string& name : files_below(dir)) {
    EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
    EXPECT_EQ(name.find(".h5.d"), std::string::npos) << name;
  }
}

// A write into the space reserved for the stop's root overwrites blocks allocated in advance:
// a disk that stays full does not fail it (io/archive_root.cpp, write_root_into_reserve).
bool writes_reserved_space(const std::string& step) {
  return step.rfind("reserved root: ", 0) == 0;
}

// The step that starts the update archiving a generation.
bool starts_a_generation(const std::string& step) {
  return step == "segment: create";
}

// A full disk for the archive writes of a fresh run: fails (ENOSPC) write step `fail_at` of
// the update that archives generation `generation` and, if `stays_full`, every write after it.
class FullDisk {
 public:
  FullDisk(std::int64_t generation, int fail_at, bool stays_full)
      : state_(std::make_shared<State>()) {
    state_->generation = generation;
    state_->fail_at = fail_at;
    state_->stays_full = stays_full;
  }
  void operator()(const std::string& step) const {
    State& s = *state_;
    if (starts_a_generation(step)) {
      ++s.updates;
      s.index = 0;
    }
    const bool hit = s.updates == s.generation + 1 && s.index == s.fail_at;
    ++s.index;
    if (hit || (s.failed && s.stays_full && !writes_reserved_space(step))) {
      s.failed = true;
      throw std::system_error(ENOSPC, std::generic_category(), step);
    }
  }
  bool failed() const { return state_->failed; }

 private:
  struct State {
    std::int64_t generation = 0;
    int fail_at = 0;
    bool stays_full = false;
    std::int64_t updates = 0;
    int index = 0;
    bool failed = false;
  };
  std::shared_ptr<State> state_;  // shared by the copies std::function makes
};

// Every write step of one run (or resume) of `config` into `out`, in order. The pack's steps
// from its creation to its close run in the pack's child process (io/child_process.hpp): the
// steps are logged to a file, which both processes append to.
std::vector<std::string> steps_of_a_run(const Config& config, const std::string& out, bool resume) {
  const std::string log = out + ".steps";
  std::filesystem::remove(log);
  run_once(config, out, resume,
           [&](const std::string& name) { std::ofstream(log, std::ios::app) << name << '\n'; });
  std::vector<std::string> all;
  std::ifstream in(log);
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::filesystem::remove(log);
  return all;
}

// The write steps of the update that archives generation 1.
std::vector<std::string> steps_of_a_generation(const Config& config, const std::string& dir) {
  std::vector<std::string> steps;
  int updates = 0;
  for (const std::string& name : steps_of_a_run(config, dir + "/count.h5", false)) {
    if (starts_a_generation(name) || name == "pack: create") ++updates;
    if (updates == 2) steps.push_back(name);
  }
  return steps;
}

namespace {

// The write-step fault tests fail or kill a run at every step of the archive's writing. The
// sanitizer build (tools/bootstrap.sh sanitize) sets SOFTEVO_TEST_STEP_STRIDE=2: each of a
// test's two passes then takes every other step, the first pass the even steps and the second
// the odd ones, so every step is still tested under the sanitizers at half the cost (these two
// tests took 7 of the sanitizer suite's 24 CPU minutes). Unset, every step in both passes.
std::size_t sampled_step_stride() {
  const char* text = std::getenv("SOFTEVO_TEST_STEP_STRIDE");
  const int stride = text != nullptr ? std::atoi(text) : 1;
  return static_cast<std::size_t>(stride >= 1 && stride <= 16 ? stride : 1);
}
std::size_t sampled_first_step(std::size_t pass) {
  return pass % sampled_step_stride();
}

}  // namespace

TEST(RunArchive, WriteStepsOfAGenerationAreKnown) {
  test::TmpDir dir;
  // The segment (written once), then the small root that links it: nothing of the earlier
  // generations is copied.
  const std::vector<std::string> expected = {"segment: create",
                                             "segment: /generations/000001",
                                             "segment: flush",
                                             "segment: close",
                                             "segment: fsync",
                                             "segment: rename",
                                             "segment: fsync directory",
                                             "root: create",
                                             "root: attributes",
                                             "root: /config",
                                             "root: /stats",
                                             "root: /generations",
                                             "root: /checkpoint",
                                             "root: flush",
                                             "root: close",
                                             "root: reserve",
                                             "root: fsync",
                                             "root: rename",
                                             "root: fsync directory"};
  EXPECT_EQ(steps_of_a_generation(small_config(), dir.path), expected);
}

// A failure at every write step of generation 1 (the disk full once, or for good) loses at
// most that generation: the archive still holds generation 0 consistently, the error names
// the real cause, and --resume (space freed) gives the digest of an uninterrupted run.
TEST(RunArchive, FailureAtEveryWriteOfAGenerationLeavesAResumableArchive) {
  const test::TmpDir dir(true);
  const Config config = small_config();
  const std::string ref = dir.file("ref.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  const std::string expected = fitness_digest_of(ref);
  const std::vector<std::string> steps = steps_of_a_generation(config, dir.path);
  ASSERT_EQ(steps.size(), 19u);

  for (bool stays_full : {false, true}) {
    for (std::size_t k = sampled_first_step(stays_full ? 1 : 0); k < steps.size();
         k += sampled_step_stride()) {
      SCOPED_TRACE("fail at step " + std::to_string(k) + " (" + steps[k] + ")" +
                   (stays_full ? ", disk stays full" : ", once"));
      const std::string out = dir.file("fault.h5");
      std::filesystem::remove(out);
      const FullDisk fault(1, static_cast<int>(k), stays_full);
      try {
        run_once(config, out, false, fault);
        ADD_FAILURE() << "the run did not fail";
      } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("--resume"), std::string::npos) << e.what();
      }
      EXPECT_TRUE(fault.failed());
      {
        // Syncing the directory comes after the rename: the new root is then in place.
        const std::int64_t kept = steps[k] == "root: fsync directory" ? 2 : 1;
        const Archive a(out);
        const io::RunInfo info = a.info();
        EXPECT_EQ(info.generations_done, kept);
        EXPECT_EQ(static_cast<std::int64_t>(a.generations().size()), kept);
        // The stop after a failed write records the state in a new small root (on a disk that
        // stays full, in the space reserved for it: issue 29, where the state stayed
        // "running"), and never packs: the pack is a second copy of every generation, and
        // libhdf5 crashed (SIGSEGV in H5Ocopy) when the disk filled during it (issue 29).
        EXPECT_EQ(info.state, io::RunState::interrupted);
        EXPECT_FALSE(a.self_contained());
        ASSERT_TRUE(a.checkpoint().has_value());
        EXPECT_EQ(a.checkpoint()->generation, kept);
      }
      ASSERT_EQ(run_once(config, out, true), RunOutcome::complete);
      EXPECT_EQ(fitness_digest_of(out), expected);
      EXPECT_EQ(Archive(out).info().state, io::RunState::complete);
      EXPECT_TRUE(Archive(out).self_contained());
      expect_no_debris(dir.path);
    }
  }
}

// A full disk while packing the finished run (it needs room for a second copy): every
// generation stays archived, the error says so, and --resume (with room again) only packs.
TEST(RunArchive, FailureWhilePackingKeepsEveryGeneration) {
  const test::TmpDir dir(true);
  const Config config = small_config();
  const std::string ref = dir.file("ref.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  std::vector<std::string> pack_steps;
  for (const std::string& step : steps_of_a_run(config, dir.file("count.h5"), false))
    if (step.rfind("pack: ", 0) == 0) pack_steps.push_back(step);
  ASSERT_GE(pack_steps.size(), 10u);
  for (const std::string& failing : pack_steps) {
    if (failing == "pack: remove segments") continue;  // after the rename: nothing to lose
    SCOPED_TRACE("disk full from " + failing + " on");
    const std::string out = dir.file("full.h5");
    io::remove_archive(out);
    bool full = false;
    try {
      run_once(config, out, false, [&](const std::string& step) {
        full = full || step == failing;
        if (full && !writes_reserved_space(step))
          throw std::system_error(ENOSPC, std::generic_category(), step);
      });
      ADD_FAILURE() << "the run did not fail";
    } catch (const RunError& e) {
      EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos)
          << e.what();
    }
    {
      const Archive a(out);
      EXPECT_EQ(a.info().generations_done, config.run.generations);
      // Syncing the directory comes after the rename: the packed archive is then in place.
      // Otherwise the final state is recorded in a small root (into the reserved space when
      // the disk stays full: "running" before, issue 29).
      const bool packed = failing == "pack: fsync directory";
      EXPECT_EQ(a.info().state, io::RunState::complete);
      EXPECT_EQ(a.self_contained(), packed);
      EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
    }
    ASSERT_EQ(run_once(config, out, true), RunOutcome::already_complete);
    EXPECT_EQ(hash_hex(io::content_digest(Archive(out))),
              hash_hex(io::content_digest(Archive(ref))));
    EXPECT_TRUE(Archive(out).self_contained());
    expect_no_debris(dir.path);
  }
}

// Runs (or resumes) `config` into `out` in a child process that is SIGKILLed just before write
// step `kill_at` (counted over the whole run, the steps in the pack's own child process
// included: a shared count); true when the child was killed there.
bool killed_at_step(const Config& config, const std::string& out, bool resume,
                    std::size_t kill_at) {
  void* shared = ::mmap(nullptr, sizeof(std::size_t), PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  EXPECT_NE(shared, MAP_FAILED);
  auto* index = static_cast<std::size_t*>(shared);
  *index = 0;
  const bool killed = killed_in_child([&] {
    const pid_t run = ::getpid();
    run_once(config, out, resume, [&](const std::string&) {
      if ((*index)++ != kill_at) return;
      ::kill(run, SIGKILL);  // the run, when this is the pack's process (which then dies too)
      ::raise(SIGKILL);
    });
  });
  ::munmap(shared, sizeof(std::size_t));
  return killed;
}

// A kill at every write step of a run - its creation, a generation (segment, root), the final
// pack - leaves an archive that --resume continues to the digests of an uninterrupted
// run, ending as one file with no temporary or segment left. Both forms of archive: a new run
// (a root with segments), and the resume of a self-contained archive (which first moves its
// file into the segment directory).
TEST(RunArchive, KillAtEveryWriteStepLeavesAResumableArchive) {
  const test::TmpDir dir(true);
  const Config config = small_config();
  const std::string ref = dir.file("ref.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  const std::string expected_fitness = fitness_digest_of(ref);
  const std::string expected_content = hash_hex(io::content_digest(Archive(ref)));

  // A self-contained archive of generations 0-1 (a failed write of generation 2, then a pack
  // as a stop by signal makes).
  const std::string packed = dir.file("packed.h5");
  EXPECT_THROW(run_once(config, packed, false, FullDisk(2, 0, false)), RunError);
  io::finish_archive(packed, Archive(packed).info());
  ASSERT_TRUE(Archive(packed).self_contained());
  ASSERT_EQ(Archive(packed).info().generations_done, 2);

  for (bool from_packed : {false, true}) {
    const std::string out = dir.file("kill.h5");
    const auto start = [&] {
      io::remove_archive(out);
      if (from_packed) std::filesystem::copy_file(packed, out);
    };
    start();
    const std::vector<std::string> steps = steps_of_a_run(config, out, from_packed);
    ASSERT_GT(steps.size(), 20u);
    if (from_packed) {
      EXPECT_EQ(steps[0], "packed: link");
    }
    // Every step but those of the second and later generations of the run, the same steps
    // again, and (resuming) those of the pack, the new run's again: this keeps the test short.
    std::vector<bool> tested(steps.size(), true);
    int generation_updates = 0;
    bool in_generation = false;
    bool packing = false;
    for (std::size_t k = 0; k < steps.size(); ++k) {
      if (starts_a_generation(steps[k])) {
        in_generation = true;
        ++generation_updates;
      }
      packing = packing || steps[k] == "pack: create";
      tested[k] = (!in_generation || generation_updates == 1) && !(from_packed && packing);
      if (steps[k] == "root: fsync directory") in_generation = false;
    }
    for (std::size_t k = sampled_first_step(from_packed ? 1 : 0); k < steps.size();
         k += sampled_step_stride()) {
      if (!tested[k]) continue;
      SCOPED_TRACE(std::string(from_packed ? "resume of a packed archive" : "new run") +
                   ", killed before step " + std::to_string(k) + " (" + steps[k] + ")");
      start();
      ASSERT_TRUE(killed_at_step(config, out, from_packed, k));
      // Killed before its root existed, a new run has nothing to resume: it starts again.
      // Killed while packing, it has every generation: the resume only packs it.
      const RunOutcome expected =
          std::filesystem::exists(out) &&
                  Archive(out).info().generations_done == config.run.generations
              ? RunOutcome::already_complete
              : RunOutcome::complete;
      ASSERT_EQ(run_once(config, out, true), expected);
      EXPECT_EQ(fitness_digest_of(out), expected_fitness);
      EXPECT_EQ(hash_hex(io::content_digest(Archive(out))), expected_content);
      EXPECT_EQ(Archive(out).info().state, io::RunState::complete);
      EXPECT_TRUE(Archive(out).self_contained());
      expect_no_debris(dir.path);
    }
  }
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A resume into a full disk fails at its first write and leaves the archive byte for byte as
// it was; with space again it completes the run.
TEST(RunArchive, ResumeIntoAFullDiskLeavesTheArchiveAsItWas) {
  test::TmpDir dir;
  const Config config = small_config();
  const std::string ref = dir.file("ref.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  const std::string out = dir.file("run.h5");
  EXPECT_THROW(run_once(config, out, false, FullDisk(2, 0, true)), RunError);
  const std::string before = file_bytes(out);
  const auto full = [](const std::string& step) {
    throw std::system_error(ENOSPC, std::generic_category(), step);
  };
  EXPECT_THROW(run_once(config, out, true, full), RunError);
  EXPECT_TRUE(file_bytes(out) == before);
  EXPECT_EQ(Archive(out).generations(), (std::vector<std::int64_t>{0, 1}));
  ASSERT_EQ(run_once(config, out, true), RunOutcome::complete);
  EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
}

// The run lock: a second run on the same archive is refused at start-up, naming the holder,
// and touches nothing; the lock of a killed process does not block the next start.
TEST(RunLock, SecondRunOnTheSameArchiveIsRefused) {
  test::TmpDir dir;
  const Config config = small_config();
  const std::string out = dir.file("run.h5");
  RunOptions options;
  options.out_path = out;
  PreparedRun first = prepare_run(config, options, 1);
  for (bool resume : {false, true}) {
    options.resume = resume;
    try {
      prepare_run(config, options, 1);
      ADD_FAILURE() << "second start accepted (resume = " << resume << ")";
    } catch (const StartupError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("another run"), std::string::npos) << m;
      EXPECT_NE(m.find("pid " + std::to_string(::getpid()) + " on " + host_name()),
                std::string::npos)
          << m;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  LocalExecutor executor(fake_evaluation);
  ProgressReporter progress = ProgressReporter::silent();
  EXPECT_EQ(execute_run(first, executor, progress), RunOutcome::complete);
}

// Issue 30: no `.lock` stays beside a finished archive. A run that ends cleanly (complete, or a
// --resume of a complete archive) removes its lock file; while a run holds the lock, a refused
// second start leaves it in place (a run that opened the old file before the removal locks
// the file then at the path: io/run_lock.hpp).
TEST(RunLock, ACleanEndRemovesTheLockFile) {
  test::TmpDir dir;
  const Config config = small_config();
  const std::string out = dir.file("run.h5");
  const std::string lock = io::lock_path_for(out);
  RunOptions options;
  options.out_path = out;
  PreparedRun first = prepare_run(config, options, 1);
  EXPECT_THROW(prepare_run(config, options, 1), StartupError);
  EXPECT_TRUE(std::filesystem::exists(lock)) << "removed while its run holds it";
  LocalExecutor executor(fake_evaluation);
  ProgressReporter progress = ProgressReporter::silent();
  EXPECT_EQ(execute_run(first, executor, progress), RunOutcome::complete);
  EXPECT_FALSE(std::filesystem::exists(lock)) << "left beside the finished archive";
  EXPECT_EQ(io::lock_holder(out), std::nullopt);
  run_once(config, out, true);  // --resume of the complete archive: nothing to do
  EXPECT_FALSE(std::filesystem::exists(lock));
}

TEST(RunLock, LockOfAKilledProcessDoesNotBlock) {
  test::TmpDir dir;
  const std::string out = dir.file("run.h5");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const io::RunLock lock(out, "child");
    const char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(1);
    ::pause();  // holds the lock until killed
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ::close(ready[0]);
  ::close(ready[1]);
  EXPECT_EQ(io::lock_holder(out),
            std::optional<std::string>("pid " + std::to_string(child) + " on child"));
  try {
    const io::RunLock probe(out, "parent");
    ADD_FAILURE() << "the child's lock was not seen";
  } catch (const io::RunLockError& e) {
    EXPECT_NE(std::string(e.what()).find("pid " + std::to_string(child) + " on child"),
              std::string::npos)
        << e.what();
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_EQ(io::lock_holder(out), std::nullopt) << "a dead holder still reported";
  EXPECT_NO_THROW(run_once(small_config(), out, true));
  EXPECT_EQ(Archive(out).info().state, io::RunState::complete);
}

// SIGTERM while the master evaluates alone: the evaluation in progress is abandoned (what
// softevo-mpi's abandon request does) and its result, even of the generation's last unit, is
// never archived; the stop is recorded and the run resumes to the uninterrupted digest.
TEST(RunArchive, AStopDuringTheLastEvaluationOfAGenerationArchivesNothingOfIt) {
  test::TmpDir dir;
  const Config config = small_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  RunOptions options;
  options.out_path = out;
  options.reuse_results = false;  // every member is a unit: the count below finds the last one
  PreparedRun run = prepare_run(config, options, 1);
  std::size_t evaluated = 0;
  const std::size_t first_generation = run.population->members().size();
  LocalExecutor executor([&](const EvalRequest& request) {
    if (++evaluated == first_generation + run.population->members().size()) {
      request_stop(StopRequest::now);  // during the last unit of generation 1
      EvalResult abandoned;
      abandoned.status = EvalStatus::timeout;
      return abandoned;
    }
    return fake_evaluation(request);
  });
  ProgressReporter progress = ProgressReporter::silent();
  const RunOutcome outcome = execute_run(run, executor, progress);
  clear_stop_request();
  run.lock.reset();  // the stopped run's process would end here
  EXPECT_EQ(outcome, RunOutcome::interrupted);
  EXPECT_EQ(Archive(out).info().state, io::RunState::interrupted);
  EXPECT_EQ(Archive(out).info().generations_done, 1);
  ASSERT_EQ(run_once(config, out, true), RunOutcome::complete);
  EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
}

// A run killed after archiving its last generation but before closing leaves "running" with
// every generation: --resume only marks it complete, and the digests are an uninterrupted run's.
TEST(RunArchive, ResumeClosesARunThatDiedAfterItsLastGeneration) {
  test::TmpDir dir;
  const Config config = small_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  ASSERT_EQ(run_once(config, out, false), RunOutcome::complete);
  io::RunInfo info = Archive(out).info();
  info.state = io::RunState::running;  // what the SIGKILL before the closing state change leaves
  info.end_time.clear();
  io::update_run_info(out, info);
  {
    RunOptions options;
    options.out_path = out;
    options.resume = true;
    const PreparedRun run = prepare_run(config, options, 1);
    ASSERT_TRUE(run.previous_run.has_value());
    EXPECT_NE(run.previous_run->find("after archiving its last generation"), std::string::npos)
        << *run.previous_run;
  }
  EXPECT_EQ(run_once(config, out, true), RunOutcome::already_complete);
  EXPECT_EQ(Archive(out).info().state, io::RunState::complete);
  EXPECT_EQ(io::content_digest(Archive(out)), io::content_digest(Archive(ref)));
}

// A run in which no evaluation succeeds stops (a config that cannot work must not burn an
// allocation): the cause is in the error and in the archive's stop_reason, and the archive is
// marked interrupted. With the threshold at 0 the run goes on.
TEST(RunStop, AGenerationWhoseEvaluationsAllFailStopsTheRun) {
  test::TmpDir dir;
  Config config = small_config();
  const auto failing = [](const EvalRequest& request) {
    EvalResult r = fake_evaluation(request);
    r.status = EvalStatus::failed;
    r.fitness = 0.0;
    r.message = "terrain: the ground cannot be built";
    return r;
  };
  const auto run = [&](const Config& c, const std::string& out) {
    RunOptions options;
    options.out_path = out;
    PreparedRun prepared = prepare_run(c, options, 1);
    LocalExecutor executor(failing);
    ProgressReporter progress = ProgressReporter::silent();
    return execute_run(prepared, executor, progress);
  };
  const std::string out = dir.file("failed.h5");
  try {
    run(config, out);
    FAIL() << "a run whose every evaluation fails went on";
  } catch (const RunError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no evaluation of generation 0"), std::string::npos) << what;
    EXPECT_NE(what.find("the ground cannot be built"), std::string::npos) << what;
    EXPECT_NE(what.find("run.stop_after_failed_generations"), std::string::npos) << what;
  }
  const io::RunInfo info = Archive(out).info();
  EXPECT_EQ(info.state, io::RunState::interrupted);
  EXPECT_EQ(info.generations_done, 1);
  EXPECT_NE(info.stop_reason.find("the ground cannot be built"), std::string::npos)
      << info.stop_reason;

  config.run.stop_after_failed_generations = 0;
  EXPECT_EQ(run(config, dir.file("goes_on.h5")), RunOutcome::complete);
  config.run.stop_after_failed_generations = 3;
  EXPECT_THROW(run(config, dir.file("three.h5")), RunError);
  EXPECT_EQ(Archive(dir.file("three.h5")).info().generations_done, 3);
}

// Killed robots are evolution's verdict, not a broken setup: a generation of them goes on.
TEST(RunStop, AGenerationOfKilledRobotsGoesOn) {
  test::TmpDir dir;
  const Config config = small_config();
  RunOptions options;
  options.out_path = dir.file("killed.h5");
  PreparedRun prepared = prepare_run(config, options, 1);
  LocalExecutor executor([](const EvalRequest& request) {
    EvalResult r = fake_evaluation(request);
    r.status = EvalStatus::killed_flipped;
    r.fitness = 0.0;
    return r;
  });
  ProgressReporter progress = ProgressReporter::silent();
  EXPECT_EQ(execute_run(prepared, executor, progress), RunOutcome::complete);
  EXPECT_TRUE(Archive(options.out_path).info().stop_reason.empty());
}

// The memory estimate before a run (issue 29: a population of 10^6 grew to 3.6 GB before
// generation 0): it grows with the population and the learning candidates; a job beyond the
// available memory is refused naming the keys to lower, one close to it is warned about.
TEST(RunMemory, EstimateRefusesBeyondAndWarnsNearTheAvailableMemory) {
  Config c = small_config();
  c.neat.pop_size = 1000;
  const std::uint64_t thousand = estimate_run_memory(c);
  c.neat.pop_size = 1000000;
  const std::uint64_t million = estimate_run_memory(c);
  EXPECT_GT(million, std::uint64_t{9} << 30);  // measured: about 9.3 kB per member
  EXPECT_GT(million, thousand * 100);
  c.learning.method = LearningMethod::es;
  EXPECT_GT(estimate_run_memory(c), million);
  c.learning.method = LearningMethod::none;
  // A larger minimum species size adds members (issue 39): at the population, each of up to
  // pop/2 species may hold that many.
  c.neat.pop_size = 1000;
  c.neat.min_species_size = 1000;
  EXPECT_GE(estimate_run_memory(c), thousand + 500ULL * 998 * kBytesPerMember);
  c.neat.min_species_size = 2;
  c.neat.elitism = 1000;
  EXPECT_GE(estimate_run_memory(c), thousand + 500ULL * 998 * kBytesPerMember);
  c.neat.elitism = small_config().neat.elitism;
  c.neat.pop_size = 1000000;

  const std::vector<const Config*> one = {&c};
  try {
    check_run_memory(one, AvailableMemory{million / 2, "test"});
    ADD_FAILURE() << "not refused";
  } catch (const StartupError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("neat.pop_size"), std::string::npos) << m;
    EXPECT_NE(m.find("--population"), std::string::npos) << m;
    EXPECT_NE(m.find("available (test)"), std::string::npos) << m;
  }
  const std::string near = check_run_memory(one, AvailableMemory{million + million / 10, "test"});
  EXPECT_NE(near.find("close to"), std::string::npos) << near;
  EXPECT_EQ(check_run_memory(one, AvailableMemory{million * 2, "test"}), "");
  EXPECT_EQ(check_run_memory(one, std::nullopt), "");
  // A --seeds job counts every run.
  const std::vector<const Config*> ten(10, &c);
  EXPECT_THROW(check_run_memory(ten, AvailableMemory{million * 5, "test"}), StartupError);
}

// The learning term of the estimate covers what learning runs take (issue 29: it was 2 KiB per
// candidate, unmeasured). Peak RSS of `softevo evolve -j 1` with 100 members, one generation
// and one learning iteration (master/run.hpp), at 4, 16 and 64 candidates: the estimate is
// above every measured peak, and grows per candidate at least as fast as they did.
TEST(RunMemory, LearningTermCoversTheMeasuredPeaks) {
  Config c = small_config();
  c.neat.pop_size = 100;
  c.learning.method = LearningMethod::es;
  struct Measured {
    std::int64_t candidates;
    std::uint64_t peak_kib;
  };
  for (const Measured m : {Measured{4, 28824}, Measured{16, 36684}, Measured{64, 66192},
                           Measured{4, 29968}, Measured{16, 39184}}) {
    c.learning.population = m.candidates;
    EXPECT_GE(estimate_run_memory(c), m.peak_kib * 1024) << m.candidates << " candidates";
  }
  // gait-closed-learn, 4 -> 16 candidates: 7.7 KiB more per candidate per member.
  const std::uint64_t closed_slope = (39184 - 29968) * 1024 / (100 * 12);
  c.learning.population = 4;
  const std::uint64_t at4 = estimate_run_memory(c);
  c.learning.population = 16;
  EXPECT_GE((estimate_run_memory(c) - at4) / (100 * 12), closed_slope);
}

// --resume of a complete archive on read-only storage reports it complete (exit 0) without
// writing or locking anything; one that would need a write fails naming the reason (issue 29:
// it exited 2 where docs/archive.md says 0). A real read-only tmpfs: root only, skipped
// elsewhere.
TEST(RunArchive, ResumeOfACompleteArchiveOnReadOnlyStorage) {
  test::TmpDir dir;
  const std::string mnt = dir.file("ro");
  std::filesystem::create_directory(mnt);
  if (::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=4m") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs (" << std::strerror(errno) << "; needs root)";
  const test::LazyUnmount unmount{mnt};
  const Config config = small_config();
  const std::string out = mnt + "/run.h5";
  ASSERT_EQ(run_once(config, out, false), RunOutcome::complete);
  std::filesystem::remove(out + ".lock");
  const std::string digest = fitness_digest_of(out);
  ASSERT_EQ(::mount("tmpfs", mnt.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, "size=4m"), 0)
      << std::strerror(errno);
  EXPECT_EQ(run_once(config, out, true), RunOutcome::already_complete);
  EXPECT_EQ(fitness_digest_of(out), digest);
  EXPECT_FALSE(std::filesystem::exists(out + ".lock"));
  Config longer = config;
  longer.run.generations += 1;
  try {
    run_once(longer, out, true);
    ADD_FAILURE() << "a longer run on read-only storage started";
  } catch (const StartupError& e) {
    EXPECT_NE(std::string(e.what()).find("Read-only file system"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace softevo::master
