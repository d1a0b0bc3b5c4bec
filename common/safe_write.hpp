// Output files written so that no failure and no hostile target loses or damages existing data.
//
// The rule every softevo command follows for a file it writes (docs/output-files.md):
// - The bytes go to a fresh temporary file ".<name>.tmp.<pid>.XXXXXX" in the target's
//   directory, created with mkstemp (O_CREAT | O_EXCL, so a planted file or symlink of the same
//   name is never followed), then fsync'ed and renamed over the target, and the directory is
//   fsync'ed: a crash leaves either the old file or the new one, never a mix.
// - The writer's pid in the temporary's name lets a later process tell the debris of a dead
//   writer (killed between mkstemp and rename) from the file a live one is writing:
//   remove_stale_temporaries() removes only the former. The run archive (io/archive.hpp) calls it
//   at every start, under its run lock.
// - The target must be absent or a regular file. A symlink, directory, FIFO, socket or device
//   (/dev/full, /dev/null) is refused: replacing it with a regular file would silently destroy
//   what it was, and following a symlink would write somewhere the user did not name.
// - An existing regular file is replaced only with Overwrite::replace (a command's --force).
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace softevo {

class OutputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Overwrite { refuse, replace };

// Throws OutputFileError "<path>: <reason>" if `path` may not be written under the rule above.
void check_output_target(const std::string& path, Overwrite overwrite);

// The directory of `path` ("." when it has none).
std::string directory_of(const std::string& path);

// Writes all of `bytes` to `fd` from its current offset (write(2) again after EINTR and after a
// short write). Returns 0, or the errno of the write that failed (ENOSPC for a write that took
// nothing), so each caller reports it in its own words.
int write_fully(int fd, std::string_view bytes);

// Fault injection for tests (may be empty): called with "fsync", "rename" and "fsync directory"
// before those steps of commit(); a hook that throws makes that step fail.
using CommitStepHook = std::function<void(const std::string& step)>;

// A temporary file beside `path` that becomes `path` on commit(). For writers that need a file
// name of their own (HDF5, libpng): write to temp_path(), then commit(). The destructor removes
// the temporary if commit() was never reached, so an exception leaves the target untouched.
class AtomicOutput {
 public:
  AtomicOutput(std::string path, Overwrite overwrite);
  // The temporary is `existing`, a file of the caller's in the target's file system (space
  // reserved in advance: io/archive_root.cpp), renamed over `path` on commit() and left in
  // place when commit() is never reached.
  AtomicOutput(std::string path, Overwrite overwrite, std::string existing);
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  ~AtomicOutput();

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

  // fsync the temporary, check the target again, rename it over the target, fsync the directory.
  // A failure before the rename leaves the target as it was (the destructor removes the
  // temporary); a failure to sync the directory comes after the rename (the new file is in
  // place) and is reported all the same, since the rename may not survive a power loss.
  void commit(const CommitStepHook& before_step = {});

 private:
  std::string path_;
  std::string temp_path_;
  Overwrite overwrite_;
  bool owns_temp_ = true;
  bool committed_ = false;
};

// write `bytes` to `path` through an AtomicOutput.
void write_file_atomically(const std::string& path, std::string_view bytes, Overwrite overwrite);

// Removes the temporaries of `path` (".<name>.tmp.<pid>.XXXXXX", and ".<name>.tmp.<pid>" of
// older builds) whose writer no longer exists; a live process's are left alone. Returns how many
// were removed.
int remove_stale_temporaries(const std::string& path);
// The same for the temporaries of every target in `directory`.
int remove_stale_temporaries_in(const std::string& directory);

}  // namespace softevo
