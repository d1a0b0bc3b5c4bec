#include "io/run_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace softevo::io {
namespace {

// What the lock file says about its holder; "" when it cannot be read (the holder may be
// between taking the lock and writing its name).
std::string read_holder(int fd) {
  char buf[512];
  const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
  if (n <= 0) return "";
  std::string text(buf, static_cast<std::size_t>(n));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\0')) text.pop_back();
  // The file is ours to read but anyone's to write: keep the message one printable line.
  for (char& c : text)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return text;
}

constexpr int kLockAttempts = 10;
constexpr useconds_t kLockRetryMicroseconds = 20000;

}  // namespace

std::optional<std::string> locked_file_note(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  int rc = 0;
  do {
    rc = ::flock(fd, LOCK_SH | LOCK_NB);
  } while (rc != 0 && errno == EINTR);
  const bool locked = rc != 0 && errno == EWOULDBLOCK;
  if (rc == 0) ::flock(fd, LOCK_UN);
  ::close(fd);
  if (!locked) return std::nullopt;
  const std::optional<std::string> run = lock_holder(path);
  return path + ": locked by another process" +
         (run ? " (a running job writes this archive: " + *run + ")"
              : std::string(" (a program that writes it through libhdf5, e.g. h5py)")) +
         ", and libhdf5 does not open a locked file; wait until it ends, or copy the file and "
         "open the copy";
}

std::optional<std::string> lock_holder(const std::string& archive_path) {
  const std::string path = lock_path_for(archive_path);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    if (errno == ENOENT) return std::nullopt;  // never locked: written before locks existed
    return "holder unknown: cannot open " + path + ": " + std::strerror(errno);
  }
  int rc = 0;
  do {
    rc = ::flock(fd, LOCK_SH | LOCK_NB);
  } while (rc != 0 && errno == EINTR);
  std::optional<std::string> holder;
  if (rc == 0) {
    ::flock(fd, LOCK_UN);
  } else if (errno == EWOULDBLOCK) {
    const std::string text = read_holder(fd);
    holder = text.empty() ? "holder unknown" : text;
  } else {
    holder = "holder unknown: cannot test " + path + ": " + std::strerror(errno);
  }
  ::close(fd);
  return holder;
}

std::string lock_path_for(const std::string& archive_path) {
  return archive_path + ".lock";
}

RunLock::RunLock(const std::string& archive_path, const std::string& host)
    : path_(lock_path_for(archive_path)) {
  // O_NOFOLLOW: a planted symlink must not make us create or truncate another file. Created
  // exclusively when absent, so abandon() knows whether the file is this start's to remove.
  for (int attempt = 0; attempt < 3 && fd_ < 0; ++attempt) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0644);
    created_ = fd_ >= 0;
    if (fd_ < 0 && errno == EEXIST) fd_ = ::open(path_.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW);
    if (fd_ < 0 && errno != ENOENT) break;  // ENOENT: removed between the two opens
  }
  if (fd_ < 0)
    throw RunLockError(path_ + ": cannot open the run lock of " + archive_path + ": " +
                       std::strerror(errno));
  // A few tries over ~0.2 s: lock_holder() of a `softevo info` holds a shared lock for
  // microseconds, which must not make a starting run fail as if another run held it.
  int rc = 0;
  for (int attempt = 0;; ++attempt) {
    rc = ::flock(fd_, LOCK_EX | LOCK_NB);
    if (rc == 0 || (errno != EINTR && errno != EWOULDBLOCK) || attempt >= kLockAttempts) break;
    if (errno == EWOULDBLOCK) ::usleep(kLockRetryMicroseconds);
  }
  if (rc != 0) {
    const int err = errno;
    const std::string holder = err == EWOULDBLOCK ? read_holder(fd_) : "";
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      throw RunLockError(archive_path + ": another run is writing this archive (" +
                         (holder.empty() ? std::string("holder unknown") : holder) + ", lock " +
                         path_ + "); wait for it to end or choose another --out");
    throw RunLockError(path_ + ": cannot lock the run lock of " + archive_path + ": " +
                       std::strerror(err));
  }
  // A start that failed (abandon()) may have removed the file while we waited for its lock: a
  // lock on a removed file excludes no one, so take the lock of the file now at the path.
  struct stat st {};
  if (::fstat(fd_, &st) == 0 && st.st_nlink == 0) {
    ::close(std::exchange(fd_, -1));
    *this = RunLock(archive_path, host);
    return;
  }
  const std::string me = "pid " + std::to_string(::getpid()) + " on " + host + "\n";
  // Best effort: the lock is what protects the archive, the text only names the holder.
  if (::ftruncate(fd_, 0) == 0) {
    const ssize_t put = ::pwrite(fd_, me.data(), me.size(), 0);
    (void)put;
  }
}

RunLock::~RunLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

void RunLock::abandon() noexcept {
  if (fd_ < 0) return;
  if (created_) ::unlink(path_.c_str());  // still locked: no one else takes it in between
  ::close(std::exchange(fd_, -1));
}

void RunLock::finish() noexcept {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // still locked: see the header for a run that opened it meanwhile
  ::close(std::exchange(fd_, -1));
}

RunLock::RunLock(RunLock&& other) noexcept
    : path_(std::move(other.path_)),
      fd_(std::exchange(other.fd_, -1)),
      created_(std::exchange(other.created_, false)) {}

RunLock& RunLock::operator=(RunLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    fd_ = std::exchange(other.fd_, -1);
    created_ = std::exchange(other.created_, false);
  }
  return *this;
}

}  // namespace softevo::io
