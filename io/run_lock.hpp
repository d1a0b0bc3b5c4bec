// The exclusive lock of one run archive: two runs on one --out must never both write it.
//
// The lock is flock(LOCK_EX) on "<archive>.lock" beside the archive (not on the archive itself:
// every generation replaces the archive by a rename, so its inode changes). The lock file
// holds "pid <pid> on <host>" of the holder, for the message of the run that is refused.
// The kernel drops an flock when its holder dies in any way (SIGKILL included), so a lock
// cannot go stale; the file of a killed run stays. A run that ends cleanly removes its lock file
// (finish()) while it still holds the lock: a run that opened the old file meanwhile gets that
// lock only after the unlink, sees the file is gone (st_nlink 0) and locks the file now at the
// path instead, so two runs never hold locks on different files of one archive.
// docs/archive.md states what this means on NFS.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

namespace softevo::io {

// Another process holds the lock, or the lock file cannot be opened; the message names the
// lock file and, when held, the holder's pid and host.
class RunLockError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "<archive_path>.lock"
std::string lock_path_for(const std::string& archive_path);

// Who holds the run lock of `archive_path` now ("pid 4242 on node17"; "holder unknown..." when
// that cannot be told), nothing if no process does. Takes a shared lock for an instant (the
// way to ask without seeing only this host's locks); RunLock retries briefly, so this never
// makes a starting run fail. Creates nothing.
std::optional<std::string> lock_holder(const std::string& archive_path);

// libhdf5 refuses to open a file that another process holds an flock on (a program writing it
// through libhdf5's file locking, e.g. h5py), so such a file looks like no HDF5 file at all.
// For that case: a message saying that `path` is locked, by which run if its run lock is held,
// and how to proceed; nullopt when no other process locks `path`.
std::optional<std::string> locked_file_note(const std::string& path);

class RunLock {
 public:
  // Takes the lock of `archive_path` without waiting and records this process (getpid(),
  // `host`) in the lock file. Throws RunLockError if another process holds it. Creates the
  // lock file if needed; touches nothing else.
  RunLock(const std::string& archive_path, const std::string& host);
  ~RunLock();
  RunLock(RunLock&& other) noexcept;
  RunLock& operator=(RunLock&& other) noexcept;
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

  const std::string& path() const { return path_; }  // the lock file

  // For a start that fails before its run wrote anything: removes the lock file if this lock
  // created it (a file that was there before stays), then releases the lock. A process that
  // opened the file meanwhile finds it locked and is refused, as it would have been.
  void abandon() noexcept;

  // For a run that ended cleanly (complete, or stopped after a checkpoint): removes the lock
  // file, created by this lock or not, then releases the lock, so no `.lock` stays beside a
  // finished archive. Only the holder calls it, so it never removes the file of another run's
  // lock.
  void finish() noexcept;

 private:
  std::string path_;
  int fd_ = -1;
  bool created_ = false;  // the lock file did not exist before this lock
};

}  // namespace softevo::io
