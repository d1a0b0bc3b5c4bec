// Where the tests that start the built `softevo` and `softevo-mpi` find them, and how they run
// them.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace softevo::test {

// The build tree: SOFTEVO_BINARY_DIR, else the parent of this test executable's folder
// (tests are built into <build>/tests).
inline std::string build_dir() {
  if (const char* dir = std::getenv("SOFTEVO_BINARY_DIR"); dir != nullptr && *dir != '\0')
    return dir;
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("build") : self.parent_path().parent_path().string();
}

inline std::string binary(const std::string& name) {
  return build_dir() + "/bin/" + name;
}

// A new folder for the running test, <tmp>/softevo_test_<prefix>_<pid>_<test name> (unique per
// process and test, so that parallel ctest runs never share one).
inline std::filesystem::path fresh_test_dir(const std::string& prefix) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("softevo_test_" + prefix + "_" + std::to_string(::getpid()) + "_" +
       ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::create_directories(dir);
  return dir;
}

struct CommandResult {
  int code = -1;       // exit status; -1 if the command could not run or died of a signal
  std::string output;  // stdout and stderr
};

// Runs `command` through the shell and collects its output (stdout and stderr).
inline CommandResult run_command(const std::string& command) {
  CommandResult r;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe) != nullptr) r.output += buf.data();
  const int status = ::pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace softevo::test
