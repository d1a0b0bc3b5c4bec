#include "common/safe_write.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
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

// ".<name>.tmp." for `path`: the part of a temporary's name before the writer's pid.
std::string temporary_prefix(const std::string& path) {
  return "." + std::filesystem::path(path).filename().string() + ".tmp.";
}

// Both write(2) loops and fsync report ENOSPC and EIO with their real cause, which the user needs
// to see ("No space left on device", not a generic "write failed").
void write_all(int fd, std::string_view bytes, const std::string& temp) {
  if (const int error = write_fully(fd, bytes)) fail(temp, "write failed: " + errno_text(error));
}

}  // namespace

int write_fully(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    if (n == 0) return ENOSPC;
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return 0;
}

std::string directory_of(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

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
  std::string pattern =
      (dir / (temporary_prefix(path_) + std::to_string(::getpid()) + ".XXXXXX")).string();
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

AtomicOutput::AtomicOutput(std::string path, Overwrite overwrite, std::string existing)
    : path_(std::move(path)),
      temp_path_(std::move(existing)),
      overwrite_(overwrite),
      owns_temp_(false) {
  check_output_target(path_, overwrite_);
}

AtomicOutput::~AtomicOutput() {
  if (!committed_ && owns_temp_ && !temp_path_.empty()) ::unlink(temp_path_.c_str());
}

void AtomicOutput::commit(const CommitStepHook& before_step) {
  const auto step = [&](const char* name) {
    if (before_step) before_step(name);
  };
  step("fsync");
  const int fd = ::open(temp_path_.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) fail(path_, "cannot reopen the temporary " + temp_path_ + ": " + errno_text(errno));
  const int synced = ::fsync(fd);
  const int sync_error = errno;
  ::close(fd);
  if (synced != 0) fail(path_, "cannot flush " + temp_path_ + ": " + errno_text(sync_error));
  // The target may have changed while we wrote (a symlink planted in the meantime).
  check_output_target(path_, overwrite_);
  step("rename");
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0)
    fail(path_, "cannot rename " + temp_path_ + " over it: " + errno_text(errno));
  committed_ = true;
  step("fsync directory");
  const std::string dir = directory_of(path_);
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd < 0)
    fail(path_, "cannot open the directory " + dir + " to flush it: " + errno_text(errno));
  const int dir_synced = ::fsync(dir_fd);
  const int dir_error = errno;
  ::close(dir_fd);
  // Some file systems cannot fsync a directory at all (EINVAL): they order the rename themselves.
  if (dir_synced != 0 && dir_error != EINVAL)
    fail(path_, "renamed into place, but cannot flush the directory " + dir + ": " +
                    errno_text(dir_error));
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

namespace {

// Removes the temporaries in `directory` whose names start with `prefix` (any ".<name>.tmp."
// when `prefix` is empty) and whose writer is dead.
int remove_dead_writers_temporaries(const std::string& directory, const std::string& prefix) {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    const std::string name = entry.path().filename().string();
    std::size_t pid_at = std::string::npos;
    if (!prefix.empty()) {
      if (name.rfind(prefix, 0) == 0) pid_at = prefix.size();
    } else if (name.size() > 1 && name[0] == '.') {
      const std::size_t tmp = name.rfind(".tmp.");
      if (tmp != std::string::npos && tmp > 1) pid_at = tmp + 5;
    }
    if (pid_at == std::string::npos) continue;
    const std::string rest = name.substr(pid_at);
    char* end = nullptr;
    const long pid = std::strtol(rest.c_str(), &end, 10);
    if (end == rest.c_str() || pid <= 0) continue;
    // "<pid>" (older builds) or "<pid>.XXXXXX" (mkstemp); anything else is not ours.
    const bool ours = *end == '\0' || (*end == '.' && std::strlen(end) == 7);
    if (!ours) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours)
    std::error_code rm;
    if (std::filesystem::remove(entry.path(), rm)) ++removed;
  }
  return removed;
}

}  // namespace

int remove_stale_temporaries(const std::string& path) {
  return remove_dead_writers_temporaries(directory_of(path), temporary_prefix(path));
}

int remove_stale_temporaries_in(const std::string& directory) {
  return remove_dead_writers_temporaries(directory, "");
}

}  // namespace softevo
