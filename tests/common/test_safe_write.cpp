// Output files: atomic, never through a symlink, never over a special file, never over an
// existing file unless asked (common/safe_write.hpp).
#include "common/safe_write.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using softevo::AtomicOutput;
using softevo::OutputFileError;
using softevo::Overwrite;
using softevo::write_file_atomically;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "softevo_safe_write.XXXXXX").string();
    path = ::mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every file in `dir` (to see that no temporary is left behind).
std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

std::string error_of(const std::string& path, Overwrite overwrite) {
  try {
    write_file_atomically(path, "new", overwrite);
  } catch (const OutputFileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(SafeWrite, NewFileIsWrittenAndNoTemporaryRemains) {
  TempDir d;
  const fs::path out = d.path / "robot.json";
  write_file_atomically(out.string(), "hello\n", Overwrite::refuse);
  EXPECT_EQ(read(out), "hello\n");
  EXPECT_EQ(entries(d.path), 1u);
  struct stat st {};
  ASSERT_EQ(::stat(out.c_str(), &st), 0);
  const mode_t mask = ::umask(0);
  ::umask(mask);
  EXPECT_EQ(st.st_mode & 0777, 0666 & ~mask);  // not mkstemp's 0600
}

TEST(SafeWrite, ExistingFileNeedsReplace) {
  TempDir d;
  const fs::path out = d.path / "x.json";
  std::ofstream(out) << "old";
  const std::string e = error_of(out.string(), Overwrite::refuse);
  EXPECT_NE(e.find(out.string()), std::string::npos) << e;
  EXPECT_NE(e.find("--force"), std::string::npos) << e;
  EXPECT_EQ(read(out), "old");
  write_file_atomically(out.string(), "new", Overwrite::replace);
  EXPECT_EQ(read(out), "new");
  EXPECT_EQ(entries(d.path), 1u);
}

TEST(SafeWrite, SymlinkTargetIsRefusedAndItsTargetUntouched) {
  TempDir d;
  const fs::path victim = d.path / "victim";
  std::ofstream(victim) << "precious";
  const fs::path link = d.path / "out.json";
  fs::create_symlink(victim, link);
  for (const Overwrite o : {Overwrite::refuse, Overwrite::replace}) {
    const std::string e = error_of(link.string(), o);
    EXPECT_NE(e.find("symbolic link"), std::string::npos) << e;
  }
  EXPECT_EQ(read(victim), "precious");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(entries(d.path), 2u);
}

TEST(SafeWrite, SpecialFilesAreRefused) {
  TempDir d;
  const fs::path fifo = d.path / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(error_of(fifo.string(), Overwrite::replace).find("a FIFO"), std::string::npos);
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_NE(error_of(d.path.string(), Overwrite::replace).find("a directory"), std::string::npos);
  EXPECT_NE(error_of("/dev/full", Overwrite::replace).find("character device"), std::string::npos);
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
  EXPECT_EQ(entries(d.path), 1u);
}

TEST(SafeWrite, UncommittedOutputLeavesNothingBehind) {
  TempDir d;
  const fs::path out = d.path / "trace.h5";
  std::ofstream(out) << "old";
  {
    AtomicOutput o(out.string(), Overwrite::replace);
    std::ofstream(o.temp_path()) << "half written";
    EXPECT_EQ(fs::path(o.temp_path()).parent_path(), d.path);  // same file system: rename works
    // no commit(): an exception in the writer lands here
  }
  EXPECT_EQ(read(out), "old");
  EXPECT_EQ(entries(d.path), 1u);
}

// A temporary carries its writer's pid, so that a later process can remove a dead writer's
// temporaries and leave a live one's alone.
TEST(SafeWrite, TemporariesOfDeadWritersAreRemoved) {
  TempDir d;
  const fs::path out = d.path / "run.h5";
  const AtomicOutput live(out.string(), Overwrite::replace);
  const std::string own = fs::path(live.temp_path()).filename().string();
  EXPECT_EQ(own.rfind(".run.h5.tmp." + std::to_string(::getpid()) + ".", 0), 0u) << own;
  const fs::path dead = d.path / ".run.h5.tmp.999999999.AbC123";  // beyond pid_max
  const fs::path old_build = d.path / ".run.h5.tmp.999999999";
  const fs::path other_target = d.path / ".other.h5.tmp.999999999.AbC123";
  const fs::path not_ours = d.path / ".run.h5.tmp.999999999.notmkstemp";
  for (const fs::path& f : {dead, old_build, other_target, not_ours}) std::ofstream(f) << "x";
  EXPECT_EQ(softevo::remove_stale_temporaries(out.string()), 2);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_FALSE(fs::exists(old_build));
  EXPECT_TRUE(fs::exists(live.temp_path()));
  EXPECT_TRUE(fs::exists(other_target));
  EXPECT_TRUE(fs::exists(not_ours));
  EXPECT_EQ(softevo::remove_stale_temporaries_in(d.path.string()), 1);  // other.h5's
  EXPECT_TRUE(fs::exists(live.temp_path()));
}

// The fault-injection hook sees the commit's steps in order; a throw there fails the commit.
TEST(SafeWrite, CommitStepsCanBeFailed) {
  TempDir d;
  const fs::path out = d.path / "a.txt";
  std::vector<std::string> steps;
  {
    AtomicOutput o(out.string(), Overwrite::refuse);
    o.commit([&](const std::string& s) { steps.push_back(s); });
  }
  EXPECT_EQ(steps, (std::vector<std::string>{"fsync", "rename", "fsync directory"}));
  {
    AtomicOutput o(out.string(), Overwrite::replace);
    std::ofstream(o.temp_path()) << "new";
    EXPECT_THROW(o.commit([](const std::string& s) {
      if (s == "rename") throw std::runtime_error("injected");
    }),
                 std::runtime_error);
  }
  EXPECT_EQ(read(out), "");
  EXPECT_EQ(entries(d.path), 1u);
}

TEST(SafeWrite, MissingDirectoryNamesThePath) {
  const std::string e = error_of("/nonexistent-dir/x.json", Overwrite::replace);
  EXPECT_NE(e.find("/nonexistent-dir/x.json"), std::string::npos) << e;
  EXPECT_NE(e.find("No such file or directory"), std::string::npos) << e;
}
