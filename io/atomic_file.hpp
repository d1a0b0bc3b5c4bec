// Crash-safe replacement of a file: the new content is written to a temporary file next to the
// target (".<name>.tmp.<pid>"), which is fsync'ed and renamed over the target; then the
// directory is fsync'ed. A crash leaves either the old or the new file, never a half-written
// one. The run archive's discipline (docs/archive.md): its temporaries carry the writer's pid,
// so that a restarted run can tell the debris of a dead writer (remove_stale_temp_files) from
// the copy a live one is editing; other outputs use common/safe_write.hpp.
#pragma once

#include <functional>
#include <string>

namespace softevo::io {

// ".<name>.tmp.<pid>" in the directory of `path`.
std::string temp_path_for(const std::string& path);
// The directory of `path` ("." when it has none).
std::string directory_of(const std::string& path);

// Copies the bytes of `from` into a new or truncated `to` (mode 0644). Throws
// std::runtime_error "<to>: cannot copy <from>: <strerror(errno)>" so that a full disk says
// "No space left on device" (std::filesystem::copy_file reports a short sendfile as EIO).
void copy_file_contents(const std::string& from, const std::string& to);

// Calls `write(temp)`, which must leave the complete new file at `temp` (closed), then moves it
// over `path`. On any failure the temporary is removed, `path` is left as it was and the
// exception propagates (std::runtime_error naming the path for the file-system steps).
// `before_step` (fault injection for tests, may be empty) is called with "fsync", "rename" and
// "fsync directory" before those steps.
void replace_atomically(const std::string& path,
                        const std::function<void(const std::string& temp)>& write,
                        const std::function<void(const std::string& step)>& before_step = {});

// Removes ".<name>.tmp.<pid>" files next to `path` left by a process that no longer exists
// (one killed while writing); returns how many were removed.
int remove_stale_temp_files(const std::string& path);

}  // namespace softevo::io
