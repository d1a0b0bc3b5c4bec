// Input files read whole (configs, robot files, steering logs) are read with a size limit, and
// only when they are regular files: a device (/dev/zero) or a huge sparse file would otherwise
// grow the process without bound, and a FIFO would block it forever. The limits are far above
// any real file of the kind (docs/output-files.md lists them) and are checked before the file is
// read whole; a file that grows past its limit while being read is refused too.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace softevo {

class InputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct InputLimits {
  static constexpr std::uint64_t config_bytes = 4ULL << 20;         // a TOML config: 4 MiB
  static constexpr std::uint64_t robot_file_bytes = 64ULL << 20;    // a robot file: 64 MiB
  static constexpr std::uint64_t steering_log_bytes = 64ULL << 20;  // a steering log: 64 MiB
};

// The bytes of the regular file `path`, at most `limit` of them. `what` names the kind of file in
// the messages ("config file", "robot file"). Throws InputFileError naming the path and the
// reason: missing or unreadable (with errno's text), a directory, FIFO, socket or device, or
// larger than `limit`. Never blocks on a FIFO (it is opened without waiting for a writer).
std::string read_input_file(const std::string& path, std::uint64_t limit, const std::string& what);

// Why `path` cannot be read as a file without opening it (symbolic links followed): "" for a
// regular file, else "is a directory", "is a FIFO (named pipe)", ... or "does not exist". For
// readers that open by name (libhdf5): opening a FIFO would block until a writer comes.
std::string not_a_regular_file(const std::string& path);

// What a regular file is by its first bytes, so that a command given a file of the wrong kind
// can say what it got and which command takes that ("a robot file", not "not an HDF5 file").
enum class FileMagic { unknown, hdf5, json, png, zip, gzip };
FileMagic file_magic(const std::string& path);  // unknown also for a missing or special file

}  // namespace softevo
