// What `softevo info` and the next start say about an archive's last run (master/run_state.hpp):
// a "running" archive whose lock is free was left by a run that died, an "interrupted" one by a
// run that stopped; both say where --resume continues. A live run and a complete archive get
// no note.
#include "master/run_state.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

namespace softevo::master {
namespace {

io::RunInfo info_with(io::RunState state, std::int64_t generations_done) {
  io::RunInfo info;
  info.state = state;
  info.generations_done = generations_done;
  return info;
}

TEST(RunState, ARunningArchiveWithAFreeLockWasLeftByARunThatDied) {
  const std::optional<std::string> note =
      previous_run_note(info_with(io::RunState::running, 4), std::nullopt);
  ASSERT_TRUE(note.has_value());
  EXPECT_EQ(*note,
            "the previous run on this archive was interrupted (its process died without closing: "
            "killed rank, node failure, ...) at generation 4; --resume continues from "
            "generation 4");
}

TEST(RunState, ARunningArchiveWhoseLockIsHeldIsALiveRun) {
  EXPECT_EQ(previous_run_note(info_with(io::RunState::running, 4), "pid 4242 on node17"),
            std::nullopt);
}

TEST(RunState, AnInterruptedArchiveSaysWhereResumeContinues) {
  for (const std::optional<std::string>& holder :
       {std::optional<std::string>(), std::optional<std::string>("pid 1 on a")}) {
    const std::optional<std::string> note =
        previous_run_note(info_with(io::RunState::interrupted, 2), holder);
    ASSERT_TRUE(note.has_value());
    EXPECT_NE(note->find("interrupted (it stopped after a signal or an error, see its log) at "
                         "generation 2; --resume continues from generation 2"),
              std::string::npos)
        << *note;
  }
}

TEST(RunState, ACompleteArchiveHasNoNote) {
  EXPECT_EQ(previous_run_note(info_with(io::RunState::complete, 10), std::nullopt), std::nullopt);
}

TEST(RunState, ResumeNoteNamesTheKeptGenerations) {
  EXPECT_EQ(resume_note(5),
            "the archive keeps generations 0-4 and --resume continues from generation 5");
  EXPECT_EQ(resume_note(0),
            "the archive holds no generation yet and --resume starts at generation 0");
}

}  // namespace
}  // namespace softevo::master
