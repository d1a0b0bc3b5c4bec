// The run archive's segment directory (docs/archive.md "On disk: while running, once
// finished"): RUN.h5.d/ holds one file per generation, written once, and the packed file of an
// archive being continued; files no root references are debris, removed at the next start.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "common/safe_write.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/archive_writer_internal.hpp"
#include "io/h5.hpp"

namespace softevo::io::detail {
namespace {

namespace fs = std::filesystem;
using h5::Charset;

constexpr const char* kSegmentFormat = "softevo.segment/1";

// The segment directory as external links name it: relative to the root file's directory,
// so the pair can be moved together.
std::string segment_directory_link_name(const std::string& path) {
  return fs::path(path).filename().string() + ".d";
}
std::string segment_file_name(std::int64_t generation) {
  return "gen-" + generation_group_name(generation) + ".h5";
}
// The former self-contained root, kept as it was, that holds generations 0..n-1 of an archive
// being continued (a finished archive, or one from an older build).
std::string packed_file_name(std::int64_t generations) {
  return "packed-" + generation_group_name(generations) + ".h5";
}
bool is_segment_file_name(const std::string& name) {
  const auto numbered = [&](const std::string& prefix) {
    return name.size() == prefix.size() + 9 && name.rfind(prefix, 0) == 0 &&
           name.compare(name.size() - 3, 3, ".h5") == 0 &&
           std::all_of(name.begin() + static_cast<std::ptrdiff_t>(prefix.size()), name.end() - 3,
                       [](char c) { return c >= '0' && c <= '9'; });
  };
  return numbered("gen-") || numbered("packed-");
}

// Copies the bytes of `from` into the existing, empty file `to`; a full disk says "No space
// left on device" (std::filesystem::copy_file reports a short sendfile as EIO).
void copy_file_contents(const std::string& from, const std::string& to) {
  const auto fail = [&](const std::string& what) {
    throw ArchiveError(to + ": cannot copy " + from + ": " + what + ": " + std::strerror(errno));
  };
  struct Fd {
    int fd = -1;
    ~Fd() {
      if (fd >= 0) ::close(fd);
    }
  };
  const Fd in{::open(from.c_str(), O_RDONLY | O_CLOEXEC)};
  if (in.fd < 0) fail("open for reading");
  Fd out{::open(to.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC)};
  if (out.fd < 0) fail("open the copy");
  std::vector<char> buffer(std::size_t{1} << 20);
  for (;;) {
    const ssize_t got = ::read(in.fd, buffer.data(), buffer.size());
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) fail("read");
    if (got == 0) break;
    if (const int error = write_fully(out.fd, {buffer.data(), static_cast<std::size_t>(got)})) {
      errno = error;
      fail("write");
    }
  }
  if (::close(std::exchange(out.fd, -1)) != 0) fail("close");
}

}  // namespace

std::string segment_directory(const std::string& path) {
  return path + ".d";
}

// The segment directory of `path`, created if needed; a symlink or non-directory there is
// refused (the archive never writes through a link).
std::string make_segment_directory(const std::string& path) {
  const std::string dir = segment_directory(path);
  if (::mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
    throw ArchiveError(dir + ": cannot create the segment directory: " + std::strerror(errno));
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw ArchiveError(dir + ": exists and is not a directory (the archive's segments go there)");
  return dir;
}

// Writes the segment of one generation (written once, never edited) and returns its link.
GenerationStorage write_segment(const std::string& path, const GenerationRecord& record,
                                const WriteSteps& steps) {
  const PartSteps step(steps, "segment");
  const std::string name = segment_file_name(record.generation);
  const std::string segment = make_segment_directory(path) + "/" + name;
  AtomicOutput out(segment, Overwrite::replace);
  {
    step("create");
    h5::File file = h5::File::create(out.temp_path(), nullptr, segment);
    file.write_string_attribute("format", kSegmentFormat, Charset::utf8);
    const std::string group = "generations/" + generation_group_name(record.generation);
    step("/" + group);
    write_generation_group(file.create_group("generations"),
                           generation_group_name(record.generation), record);
    step("flush");
    file.flush();
    step("close");
    file.close();
  }
  out.commit(step.commit_hook());
  return GenerationStorage{record.generation, segment_directory_link_name(path) + "/" + name,
                           "/generations/" + generation_group_name(record.generation)};
}

// A root that still holds generation data (a finished archive being continued, or one written
// by an older build) becomes a small root first: the file as it is moves, unchanged, into the
// segment directory as packed-<n>.h5 (a hard link: no byte is copied; a copy where the file
// system has no hard links), and its generations become links into it.
void keep_generation_data_apart(const std::string& path, RootContent& c, const WriteSteps& steps) {
  if (!c.holds_generation_data()) return;
  const PartSteps step(steps, "packed");
  std::int64_t held = 0;
  for (const GenerationStorage& s : c.generations)
    if (s.file.empty()) held = std::max(held, s.generation + 1);
  const std::string name = packed_file_name(held);
  const std::string packed = make_segment_directory(path) + "/" + name;
  AtomicOutput out(packed, Overwrite::replace);
  step("link");
  ::unlink(out.temp_path().c_str());
  if (::link(path.c_str(), out.temp_path().c_str()) != 0) {
    const int fd = ::open(out.temp_path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) throw ArchiveError(out.temp_path() + ": cannot create: " + std::strerror(errno));
    ::close(fd);
    step("copy");
    copy_file_contents(path, out.temp_path());
  }
  out.commit(step.commit_hook());
  for (GenerationStorage& s : c.generations)
    if (s.file.empty()) s.file = segment_directory_link_name(path) + "/" + name;
}

// Removes the segment directory's files that the root at `path` does not reference (all of
// them when `path` references none, e.g. a finished archive), stale temporaries included, and
// the directory once empty. Nothing is removed when the root exists but cannot be read.
int remove_unreferenced_segments(const std::string& path) {
  const std::string dir = segment_directory(path);
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return 0;
  std::vector<std::string> referenced;
  bool packed = false;
  const bool root_exists = fs::exists(path);
  if (root_exists) {
    try {
      const Archive root(path);
      for (const GenerationStorage& s : root.generation_storage()) {
        referenced.push_back(s.file);
        packed = packed || s.file.empty();
      }
    } catch (const std::exception&) {
      return 0;  // a damaged root: its segments may be all that is left of the run
    }
  }
  int removed = remove_stale_temporaries_in(dir);
  std::error_code ec;
  // The reserved space belongs to a root in its running form (or a new one, without
  // generations yet); without a root, or beside a packed archive, it is debris.
  if (!root_exists || packed)
    if (fs::remove(reserved_root_path(path), ec)) ++removed;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string as_linked = segment_directory_link_name(path) + "/" + name;
    if (!is_segment_file_name(name) ||
        std::find(referenced.begin(), referenced.end(), as_linked) != referenced.end())
      continue;
    std::error_code rm;
    if (fs::remove(entry.path(), rm)) ++removed;
  }
  if (fs::is_empty(dir, ec)) fs::remove(dir, ec);
  return removed;
}

}  // namespace softevo::io::detail
