// A fresh directory under /tmp for one test, removed with everything in it afterwards.
// `in_memory`: under /dev/shm when there is one (a tmpfs: fsync costs nothing there, which
// keeps the tests that write an archive hundreds of times fast; what is written is the same).
#pragma once

#include <sys/mount.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace softevo::test {

struct TmpDir {
  std::string path;
  explicit TmpDir(bool in_memory = false) {
    std::string pattern = "/tmp/softevo-io-test-XXXXXX";
    if (in_memory && ::access("/dev/shm", W_OK) == 0) pattern = "/dev/shm/softevo-io-test-XXXXXX";
    path = ::mkdtemp(pattern.data());
  }
  ~TmpDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TmpDir(const TmpDir&) = delete;
  TmpDir& operator=(const TmpDir&) = delete;
  std::string file(const std::string& name) const { return path + "/" + name; }
};

// Unmounts (lazily) the file system a test mounted at `path` when it goes out of scope.
struct LazyUnmount {
  std::string path;
  ~LazyUnmount() { ::umount2(path.c_str(), MNT_DETACH); }
};

}  // namespace softevo::test
