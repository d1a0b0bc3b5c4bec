// Where the tests that start the built `softevo` and `softevo-mpi` find them.
#pragma once

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

}  // namespace softevo::test
