// See input_file.hpp.
#include "common/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string_view>

namespace softevo {

namespace {

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  return "not a regular file";
}

std::string mib(std::uint64_t bytes) {
  return std::to_string(bytes >> 20) + " MiB";
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

}  // namespace

std::string read_input_file(const std::string& path, std::uint64_t limit, const std::string& what) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer; the type is
  // checked on the open descriptor (no window between a check and the open).
  const Fd fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY));
  if (fd.get() < 0)
    throw InputFileError(path + ": cannot open " + what + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0)
    throw InputFileError(path + ": cannot read " + what + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    throw InputFileError(path + ": is " + kind_of(st.st_mode) + ", not a " + what +
                         " (only regular files are read)");
  const auto size = static_cast<std::uint64_t>(st.st_size);
  const std::string too_large = path + ": " + what + " larger than the limit of " + mib(limit) +
                                " (" + std::to_string(limit) + " bytes)";
  if (size > limit) throw InputFileError(too_large + ": it has " + std::to_string(size) + " bytes");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  std::size_t have = 0;
  for (;;) {
    if (have == bytes.size()) {
      if (bytes.size() > limit) throw InputFileError(too_large + " (it grew while being read)");
      bytes.resize(bytes.size() + 4096);  // the file may have grown; EOF ends the loop
    }
    const ssize_t n = ::read(fd.get(), bytes.data() + have, bytes.size() - have);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputFileError(path + ": read error in " + what + ": " + std::strerror(errno));
    }
    if (n == 0) break;
    have += static_cast<std::size_t>(n);
  }
  bytes.resize(have);
  if (have > limit) throw InputFileError(too_large + " (it grew while being read)");
  return bytes;
}

std::string not_a_regular_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    return errno == ENOENT ? "does not exist"
                           : std::string("cannot be read: ") + std::strerror(errno);
  return S_ISREG(st.st_mode) ? "" : "is " + kind_of(st.st_mode);
}

FileMagic file_magic(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return FileMagic::unknown;
  std::ifstream in(path, std::ios::binary);
  char head[16] = {};
  in.read(head, sizeof head);
  const std::string_view bytes(head, static_cast<std::size_t>(in.gcount()));
  if (bytes.starts_with("\x89HDF\r\n\x1a\n")) return FileMagic::hdf5;
  if (bytes.starts_with("\x89PNG")) return FileMagic::png;
  if (bytes.starts_with("PK\x03\x04")) return FileMagic::zip;
  if (bytes.starts_with("\x1f\x8b")) return FileMagic::gzip;
  const std::size_t first = bytes.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && bytes[first] == '{') return FileMagic::json;
  return FileMagic::unknown;
}

}  // namespace softevo
