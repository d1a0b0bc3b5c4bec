#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <utility>
#include <vector>

namespace softevo::io {
namespace {

namespace fs = std::filesystem;

void fsync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) throw std::runtime_error(path + ": cannot open for fsync: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) throw std::runtime_error(path + ": fsync failed: " + std::strerror(err));
}

// Closes a descriptor when it goes out of scope.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

void copy_file_contents(const std::string& from, const std::string& to) {
  const auto fail = [&](const std::string& what) {
    throw std::runtime_error(to + ": cannot copy " + from + ": " + what + ": " +
                             std::strerror(errno));
  };
  const Fd in{::open(from.c_str(), O_RDONLY | O_CLOEXEC)};
  if (in.fd < 0) fail("open for reading");
  Fd out{::open(to.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)};
  if (out.fd < 0) fail("create");
  std::vector<char> buffer(std::size_t{1} << 20);
  for (;;) {
    const ssize_t got = ::read(in.fd, buffer.data(), buffer.size());
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) fail("read");
    if (got == 0) break;
    for (ssize_t done = 0; done < got;) {
      const ssize_t put =
          ::write(out.fd, buffer.data() + done, static_cast<std::size_t>(got - done));
      if (put < 0 && errno == EINTR) continue;
      if (put < 0) fail("write");
      done += put;
    }
  }
  const int rc = ::close(std::exchange(out.fd, -1));
  if (rc != 0) fail("close");
}

std::string temp_path_for(const std::string& path) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  return (dir / ("." + p.filename().string() + ".tmp." + std::to_string(::getpid()))).string();
}

std::string directory_of(const std::string& path) {
  const fs::path p(path);
  return p.has_parent_path() ? p.parent_path().string() : std::string(".");
}

void replace_atomically(const std::string& path,
                        const std::function<void(const std::string& temp)>& write,
                        const std::function<void(const std::string& step)>& before_step) {
  const auto step = [&](const char* name) {
    if (before_step) before_step(name);
  };
  const std::string temp = temp_path_for(path);
  std::error_code ec;
  fs::remove(temp, ec);
  try {
    write(temp);
    step("fsync");
    fsync_path(temp, false);
    step("rename");
    if (std::rename(temp.c_str(), path.c_str()) != 0)
      throw std::runtime_error(path + ": cannot rename " + temp +
                               " over it: " + std::strerror(errno));
    step("fsync directory");
    fsync_path(directory_of(path), true);
  } catch (const fs::filesystem_error& e) {
    fs::remove(temp, ec);
    throw std::runtime_error(path + ": " + e.what());
  } catch (...) {
    fs::remove(temp, ec);
    throw;
  }
}

int remove_stale_temp_files(const std::string& path) {
  const std::string prefix = "." + fs::path(path).filename().string() + ".tmp.";
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(directory_of(path), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(prefix.size());
    char* end = nullptr;
    const long pid = std::strtol(rest.c_str(), &end, 10);
    if (end == rest.c_str() || pid <= 0) continue;
    // ".probe" files and copies of live processes are left alone.
    if (*end != '\0' || (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)) continue;
    std::error_code rm;
    if (fs::remove(entry.path(), rm)) ++removed;
  }
  return removed;
}

}  // namespace softevo::io
