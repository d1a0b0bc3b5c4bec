#include "common/safe_write.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

namespace softevo {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
  throw OutputFileError(path + ": " + reason);
}

std::string errno_text(int error) {
  return std::strerror(error);
}

std::string file_kind(mode_t mode) {
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  return "not a regular file";
}

std::filesystem::path directory_of(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::filesystem::path(".") : parent;
}

// Both write(2) loops and fsync report ENOSPC and EIO with their real cause, which the user needs
// to see ("No space left on device", not a generic "write failed").
void write_all(int fd, std::string_view bytes, const std::string& temp) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(temp, "write failed: " + errno_text(errno));
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
}

}  // namespace

void check_output_target(const std::string& path, Overwrite overwrite) {
  if (path.empty()) fail("(empty path)", "no output file name given");
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    fail(path, "cannot inspect the output target: " + errno_text(errno));
  }
  if (!S_ISREG(st.st_mode))
    fail(path, "refusing to write: the target is " + file_kind(st.st_mode) +
                   " (outputs must be new or regular files)");
  if (overwrite == Overwrite::refuse)
    fail(path, "refusing to overwrite an existing file (pass --force to replace it)");
}

AtomicOutput::AtomicOutput(std::string path, Overwrite overwrite)
    : path_(std::move(path)), overwrite_(overwrite) {
  check_output_target(path_, overwrite_);
  const std::filesystem::path dir = directory_of(path_);
  const std::string name = std::filesystem::path(path_).filename().string();
  std::string pattern = (dir / ("." + name + ".tmp.XXXXXX")).string();
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back('\0');
  const int fd = ::mkstemp(buf.data());
  if (fd < 0)
    fail(path_, "cannot create a temporary file in " + dir.string() + ": " + errno_text(errno));
  // mkstemp creates 0600; an output is as readable as any file the user creates (umask applies).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  ::close(fd);
  temp_path_.assign(buf.data());
}

AtomicOutput::~AtomicOutput() {
  if (!committed_ && !temp_path_.empty()) ::unlink(temp_path_.c_str());
}

void AtomicOutput::commit() {
  const int fd = ::open(temp_path_.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) fail(path_, "cannot reopen the temporary " + temp_path_ + ": " + errno_text(errno));
  const int synced = ::fsync(fd);
  const int sync_error = errno;
  ::close(fd);
  if (synced != 0) fail(path_, "cannot flush " + temp_path_ + ": " + errno_text(sync_error));
  // The target may have changed while we wrote (a symlink planted in the meantime).
  check_output_target(path_, overwrite_);
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0)
    fail(path_, "cannot rename " + temp_path_ + " over it: " + errno_text(errno));
  committed_ = true;
  const int dir_fd = ::open(directory_of(path_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);  // best effort: the rename is done; some file systems refuse directory fsync
    ::close(dir_fd);
  }
}

void write_file_atomically(const std::string& path, std::string_view bytes, Overwrite overwrite) {
  AtomicOutput out(path, overwrite);
  const int fd = ::open(out.temp_path().c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) fail(path, "cannot open the temporary " + out.temp_path() + ": " + errno_text(errno));
  try {
    write_all(fd, bytes, out.temp_path());
  } catch (...) {
    ::close(fd);
    throw;
  }
  if (::close(fd) != 0) fail(path, "cannot close " + out.temp_path() + ": " + errno_text(errno));
  out.commit();
}

}  // namespace softevo
