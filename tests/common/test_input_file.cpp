// Input files read whole (common/input_file.hpp): regular files only, each kind with its size
// limit, checked before the file is read. A device, a FIFO or a huge sparse file used to grow the
// process without bound or block it forever; through the config and robot readers too.
#include "common/input_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>

#include "common/config.hpp"
#include "common/robot.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;

struct Dir {
  fs::path path;
  Dir() {
    std::string pattern = (fs::temp_directory_path() / "softevo-input-XXXXXX").string();
    path = ::mkdtemp(pattern.data());
  }
  ~Dir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string error_of(const std::function<void()>& read) {
  try {
    read();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// A sparse file of `bytes`: takes no disk, reads as zeros.
std::string sparse(const Dir& dir, const std::string& name, std::uint64_t bytes) {
  const std::string p = (dir.path / name).string();
  { std::ofstream(p).put('{'); }
  fs::resize_file(p, bytes);
  return p;
}

TEST(InputFile, ReadsARegularFileWhole) {
  Dir dir;
  const std::string p = (dir.path / "a.txt").string();
  std::ofstream(p) << "hello";
  EXPECT_EQ(read_input_file(p, 5, "test file"), "hello");
  EXPECT_EQ(error_of([&] { read_input_file(p, 4, "test file"); }),
            p + ": test file larger than the limit of 0 MiB (4 bytes): it has 5 bytes");
}

TEST(InputFile, DevicesAndFifosAreRefusedWithoutReadingOrWaiting) {
  Dir dir;
  const std::string fifo = (dir.path / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(error_of([&] { read_input_file(fifo, 1 << 20, "robot file"); }),
            fifo + ": is a FIFO (named pipe), not a robot file (only regular files are read)");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  EXPECT_EQ(error_of([] { read_input_file("/dev/zero", 1 << 20, "robot file"); }),
            "/dev/zero: is a character device, not a robot file (only regular files are read)");
  EXPECT_NE(
      error_of([&] { read_input_file(dir.path.string(), 1 << 20, "x"); }).find("is a directory"),
      std::string::npos);
  EXPECT_NE(error_of([&] {
              read_input_file((dir.path / "none").string(), 1, "config file");
            }).find(": cannot open config file: No such file or directory"),
            std::string::npos);
  // Through the readers of each kind.
  EXPECT_THROW(read_robot_file("/dev/zero"), RobotFileError);
  EXPECT_THROW(read_robot_file(fifo), RobotFileError);
  EXPECT_THROW(load_config(fifo), ConfigError);
  EXPECT_THROW(load_config("/dev/zero"), ConfigError);
}

TEST(InputFile, EachKindHasItsLimit) {
  Dir dir;
  const std::string robot = sparse(dir, "big.robot.json", InputLimits::robot_file_bytes + 1);
  EXPECT_NE(error_of([&] {
              read_robot_file(robot);
            }).find(": robot file larger than the limit of 64 MiB"),
            std::string::npos);
  const std::string config = sparse(dir, "big.toml", InputLimits::config_bytes + 1);
  EXPECT_NE(
      error_of([&] { load_config(config); }).find(": config file larger than the limit of 4 MiB"),
      std::string::npos);
  // 10 GB, sparse: refused at once, nothing read.
  const std::string huge = sparse(dir, "huge.robot.json", 10'000'000'000ULL);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_THROW(read_robot_file(huge), RobotFileError);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
}

}  // namespace
}  // namespace softevo
