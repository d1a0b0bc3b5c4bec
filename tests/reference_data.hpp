// Where tests find the thesis reference data (the 40 champions as robot files). It lives beside
// the repository, in ../shared/reference, and is not part of a clone: tests that need it skip
// with a message naming this path when it is absent.
#pragma once

#include <cstdlib>
#include <filesystem>

namespace softevo::test {

// <source tree>/../shared/reference/bestbots (the source tree from SOFTEVO_SOURCE_DIR, which
// ctest sets, else the working directory).
inline std::filesystem::path reference_bestbots() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  const std::filesystem::path root =
      env ? std::filesystem::path(env) : std::filesystem::current_path();
  return root / ".." / "shared" / "reference" / "bestbots";
}

}  // namespace softevo::test
