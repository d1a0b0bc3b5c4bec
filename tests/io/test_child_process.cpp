// Forked children for the work that may crash libhdf5 (io/child_process.hpp): what the parent
// learns of a child that finished, threw or crashed, and that this process lives on.
#include "io/child_process.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <stdexcept>
#include <string>

namespace softevo::io {
namespace {

TEST(ChildProcess, FinishedChildGivesNoMessage) {
  EXPECT_EQ(run_in_child("the test", [] {}), "");
}

TEST(ChildProcess, ThrownErrorIsTheMessage) {
  EXPECT_EQ(run_in_child("the test", [] { throw std::runtime_error("disk full: 12 bytes free"); }),
            "disk full: 12 bytes free");
}

// The crash of the child is a message naming the signal; a crash handler of this process (Open
// MPI installs one that prints a backtrace) does not run in the child.
TEST(ChildProcess, CrashIsNamedAndCostsOnlyTheChild) {
  struct sigaction previous {};
  struct sigaction handler {};
  handler.sa_handler = [](int) { ::_exit(42); };
  sigemptyset(&handler.sa_mask);
  ASSERT_EQ(::sigaction(SIGSEGV, &handler, &previous), 0);
  const std::string message = run_in_child("the pack", [] { ::raise(SIGSEGV); });
  ::sigaction(SIGSEGV, &previous, nullptr);
  EXPECT_NE(message.find("libhdf5 crashed (signal 11: Segmentation fault)"), std::string::npos)
      << message;
  EXPECT_NE(message.find("the pack"), std::string::npos) << message;
}

// Changes the child makes to its memory stay there.
TEST(ChildProcess, ChildWorksOnACopyOfThisProcess) {
  int value = 1;
  EXPECT_EQ(run_in_child("the test", [&] { value = 2; }), "");
  EXPECT_EQ(value, 1);
}

}  // namespace
}  // namespace softevo::io
