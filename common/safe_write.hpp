// Output files written so that no failure and no hostile target loses or damages existing data.
//
// The rule every softevo command follows for a file it writes (docs/output-files.md):
// - The bytes go to a fresh temporary file in the target's directory, created with mkstemp
//   (O_CREAT | O_EXCL, so a planted file or symlink of the same name is never followed), then
//   fsync'ed and renamed over the target, and the directory is fsync'ed: a crash leaves either
//   the old file or the new one, never a mix.
// - The target must be absent or a regular file. A symlink, directory, FIFO, socket or device
//   (/dev/full, /dev/null) is refused: replacing it with a regular file would silently destroy
//   what it was, and following a symlink would write somewhere the user did not name.
// - An existing regular file is replaced only with Overwrite::replace (a command's --force).
#pragma once

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

// A temporary file beside `path` that becomes `path` on commit(). For writers that need a file
// name of their own (HDF5, libpng): write to temp_path(), then commit(). The destructor removes
// the temporary if commit() was never reached, so an exception leaves the target untouched.
class AtomicOutput {
 public:
  AtomicOutput(std::string path, Overwrite overwrite);
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  ~AtomicOutput();

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

  // fsync the temporary, check the target again, rename it over the target, fsync the directory.
  void commit();

 private:
  std::string path_;
  std::string temp_path_;
  Overwrite overwrite_;
  bool committed_ = false;
};

// write `bytes` to `path` through an AtomicOutput.
void write_file_atomically(const std::string& path, std::string_view bytes, Overwrite overwrite);

}  // namespace softevo
