// A fresh directory under /tmp for one test, removed with everything in it afterwards.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace softevo::test {

struct TmpDir {
  std::string path;
  TmpDir() {
    char pattern[] = "/tmp/softevo-io-test-XXXXXX";
    path = ::mkdtemp(pattern);
  }
  ~TmpDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TmpDir(const TmpDir&) = delete;
  TmpDir& operator=(const TmpDir&) = delete;
  std::string file(const std::string& name) const { return path + "/" + name; }
};

}  // namespace softevo::test
