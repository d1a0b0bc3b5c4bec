// The structure probe of io/open_probe.hpp: a forked child reads all of a file through libhdf5
// before this process does, so a file that crashes libhdf5 costs an error, not the process.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "io/child_process.hpp"
#include "io/h5.hpp"
#include "io/open_probe.hpp"

namespace softevo::io {
namespace {
std::atomic<bool> probe_enabled{true};
}  // namespace

void set_open_probe(bool enabled) {
  probe_enabled = enabled;
}

bool open_probe_enabled() {
  return probe_enabled;
}

}  // namespace softevo::io

namespace softevo::io::h5 {
namespace {

// Bounds of the walk: softevo's files are 3 levels deep with a few dozen objects per generation;
// a damaged or hostile file must not make the child walk for ever (cycles are cut by `seen_`).
constexpr int kMaxDepth = 64;
constexpr std::size_t kMaxObjects = 10'000'000;
constexpr hsize_t kMaxLinksPerGroup = hsize_t{1} << 24;
constexpr int kMaxAttributes = 1 << 16;
constexpr ssize_t kMaxNameBytes = 4096;
// Data is read in blocks of at most this many bytes, so the child needs no more memory than
// the readers would.
constexpr std::size_t kReadBlockBytes = std::size_t{16} << 20;
// The child's time: generous for a good file on a slow file system (it reads each byte about
// once), short enough that a file on which libhdf5 loops is refused.
constexpr double kProbeBaseSeconds = 120.0;
constexpr double kProbeBytesPerSecond = 8.0 * 1024 * 1024;
constexpr int kProbeOk = 0;
// libhdf5 sizes some buffers by length fields it reads from the file unchecked (a variable-length
// attribute's sequence length, u32 per element, sits in an unchecksummed object header): one
// flipped byte made it allocate and fill 1.9 GB to read a 25 kB archive, another 10 GB in 14 s
// (found by fuzzing). The readers cannot bound such an allocation before libhdf5 makes it, so
// the child does, and the file is refused before this process makes it:
// - the child's address space may grow by at most this allowance (RLIMIT_AS), so libhdf5's
//   allocation fails at once instead of filling gigabytes; libhdf5 reports that failure as an
//   error of the read, which the child recognises (allocation_failed);
// - where no limit can be set, its peak resident memory may grow by at most the allowance.
// A good file needs at most a few blocks of its data at once (kReadBlockBytes); the allowance is
// far above that and scales with the file. (It also leaves room for AddressSanitizer, whose
// quarantine keeps up to 256 MB of freed memory mapped.)
constexpr std::uint64_t kProbeMemoryBaseBytes = std::uint64_t{512} << 20;
constexpr std::uint64_t kProbeMemoryPerFileByte = 4;
constexpr int kProbeExcessMemory = 3;

std::uint64_t probe_memory_allowance(std::uint64_t file_bytes) {
  return kProbeMemoryBaseBytes + kProbeMemoryPerFileByte * file_bytes;
}

// Peak resident memory of this process so far (Linux reports kilobytes).
std::uint64_t peak_resident_bytes() {
  struct rusage usage {};
  if (::getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;
}

// Limits this process's address space to its present size plus `allowance` bytes.
void limit_address_space_growth(std::uint64_t allowance) {
  // The size in pages is the first field of /proc/self/statm (read without stdio: this is a
  // forked child).
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  char text[64] = {0};
  const ssize_t got = ::read(fd, text, sizeof text - 1);
  ::close(fd);
  if (got <= 0) return;
  const std::uint64_t pages = std::strtoull(text, nullptr, 10);
  if (pages == 0) return;
  const std::uint64_t size = pages * static_cast<std::uint64_t>(::getpagesize());
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) != 0) return;
  const std::uint64_t wanted = size + allowance;
  if (limit.rlim_max != RLIM_INFINITY && wanted > limit.rlim_max) return;
  limit.rlim_cur = static_cast<rlim_t>(wanted);
  ::setrlimit(RLIMIT_AS, &limit);
}

// Whether a refusal of the readers was libhdf5 (or the C++ library) running out of memory: the
// innermost message of libhdf5's error stack names the minor error H5E_NOSPACE or H5E_CANTALLOC.
bool allocation_failed(const std::exception& e) {
  if (dynamic_cast<const std::bad_alloc*>(&e) != nullptr) return true;
  const std::string message = e.what();
  for (const char* minor :
       {"No space available for allocation", "Can't allocate space", "memory allocation failed"})
    if (message.find(minor) != std::string::npos) return true;
  return false;
}

// Set in the probe's child (one thread: the fork's) when a step of the walk ran out of memory.
bool walk_ran_out_of_memory = false;

// Runs one step of the walk; a refusal (h5::Error, or any other exception of the readers) is
// not a crash, and the walk goes on with the next step: the parent may read what comes after.
template <typename Step>
void tolerate(Step step) {
  try {
    step();
  } catch (const std::exception& e) {
    if (allocation_failed(e)) walk_ran_out_of_memory = true;
    take_error_message();
  }
}

// Visits everything libhdf5 decodes when softevo's readers use the file.
class Walker {
 public:
  void object(hid_t obj, const Where& where, int depth) {
    if (depth > kMaxDepth || visited_ >= kMaxObjects) return;
    hsize_t attributes = 0;
    if (!first_visit(obj, &attributes)) return;
    ++visited_;
    tolerate([&] { read_attributes(obj, where, attributes); });
    switch (H5Iget_type(obj)) {
      case H5I_GROUP:
        tolerate([&] { walk_group(obj, where, depth); });
        break;
      case H5I_DATASET:
        tolerate([&] { read_dataset(obj, where); });
        break;
      default:  // a committed datatype: its header was decoded by first_visit
        break;
    }
  }

 private:
  // Decodes the object's header (and, where the library offers it, the sizes of its B-trees and
  // heaps); false when it was seen before or cannot be identified.
  bool first_visit(hid_t obj, hsize_t* attributes) {
    std::string key;
#if H5_VERSION_GE(1, 12, 0)
    H5O_info2_t info{};
    if (H5Oget_info3(obj, &info, H5O_INFO_ALL) < 0) return false;
    H5O_native_info_t native{};
    (void)H5Oget_native_info(obj, &native, H5O_NATIVE_INFO_ALL);
    key = std::to_string(info.fileno) + ":" +
          std::string(reinterpret_cast<const char*>(&info.token), sizeof info.token);
#else
    H5O_info_t info{};
    if (H5Oget_info2(obj, &info, H5O_INFO_ALL) < 0) return false;
    key = std::to_string(info.fileno) + ":" + std::to_string(info.addr);
#endif
    *attributes = info.num_attrs;
    return seen_.insert(std::move(key)).second;
  }

  static void read_attributes(hid_t obj, const Where& where, hsize_t count) {
    const Dataset view(Id(obj, nullptr), where);  // not owning: `obj` is closed by the caller
    const hsize_t n = std::min<hsize_t>(count, kMaxAttributes);
    for (hsize_t i = 0; i < n; ++i) {
      tolerate([&] {
        const Id attr(
            H5Aopen_by_idx(obj, ".", H5_INDEX_NAME, H5_ITER_INC, i, H5P_DEFAULT, H5P_DEFAULT),
            H5Aclose);
        if (!attr.valid()) return;
        const ssize_t size = H5Aget_name(attr.get(), 0, nullptr);
        if (size < 0 || size > kMaxNameBytes) return;
        std::string name(static_cast<std::size_t>(size) + 1, '\0');
        if (H5Aget_name(attr.get(), name.size(), name.data()) < 0) return;
        name.resize(static_cast<std::size_t>(size));
        const Id type(H5Aget_type(attr.get()), H5Tclose);
        const Id space(H5Aget_space(attr.get()), H5Sclose);
        if (!type.valid() || !space.valid()) return;
        if (H5Tis_variable_str(type.get()) > 0) {
          // As the readers read it: by name, after the file's heaps are checked.
          (void)view.read_string_attribute(name);
          return;
        }
        if (H5Tdetect_class(type.get(), H5T_VLEN) != 0) return;  // no reader reads these
        const hssize_t points = H5Sget_simple_extent_npoints(space.get());
        const std::size_t bytes = H5Tget_size(type.get());
        if (points < 0 || bytes == 0 || static_cast<std::size_t>(points) > kReadBlockBytes / bytes)
          return;
        std::vector<unsigned char> buffer(static_cast<std::size_t>(points) * bytes);
        (void)H5Aread(attr.get(), type.get(), buffer.data());
      });
    }
  }

  // What libhdf5 decodes of a dataset when the readers read it: the datatype, dataspace and
  // creation messages (layout, chunking, filters), the storage address and size, and for a
  // chunked dataset its chunk index (every chunk is read). Contiguous data is plain bytes to
  // libhdf5, and variable-length data the readers parse themselves (io/h5.cpp): neither is read.
  static void read_dataset(hid_t obj, const Where& where) {
    const Dataset ds(Id(obj, nullptr), where);
    const Id type(where.check(H5Dget_type(obj), "get the datatype"), H5Tclose);
    const Id creation(where.check(H5Dget_create_plist(obj), "get the creation properties"),
                      H5Pclose);
    const int filters = H5Pget_nfilters(creation.get());
    for (int f = 0; f < std::min(filters, 32); ++f) {
      unsigned flags = 0;
      std::size_t values = 8;
      unsigned cd_values[8] = {0};
      char name[64] = {0};
      unsigned config = 0;
      (void)H5Pget_filter2(creation.get(), static_cast<unsigned>(f), &flags, &values, cd_values,
                           sizeof name, name, &config);
    }
    (void)H5Dget_offset(obj);
    (void)H5Dget_storage_size(obj);
    if (H5Pget_layout(creation.get()) != H5D_CHUNKED) return;
    if (H5Tdetect_class(type.get(), H5T_VLEN) != 0 || H5Tis_variable_str(type.get()) > 0) return;
    const hsize_t points = ds.checked_points();  // bounded by the file's size
    const std::size_t value_bytes = H5Tget_size(type.get());
    const std::vector<hsize_t> dims = ds.dims();
    if (points == 0 || value_bytes == 0 || dims.empty()) return;
    // Blocks of whole rows along the first axis, so the child needs no more memory than the
    // readers.
    const hsize_t row_bytes = std::max<hsize_t>(1, points / dims[0] * value_bytes);
    const hsize_t rows_per_block = std::max<hsize_t>(1, kReadBlockBytes / row_bytes);
    Dataspace file_space = ds.space();
    for (hsize_t row = 0; row < dims[0]; row += rows_per_block) {
      std::vector<hsize_t> start(dims.size(), 0), count = dims;
      start[0] = row;
      count[0] = std::min(rows_per_block, dims[0] - row);
      file_space.select_block(start, count);
      const Dataspace memory_space = Dataspace::simple(count);
      std::vector<unsigned char> buffer(static_cast<std::size_t>(memory_space.points()) *
                                        value_bytes);
      if (H5Dread(obj, type.get(), memory_space.id(), file_space.id(), H5P_DEFAULT, buffer.data()) <
          0)
        return;
    }
  }

  void walk_group(hid_t obj, const Where& where, int depth) {
    const Group group(Id(obj, nullptr), where);
    for (const std::string& name : group.link_names(kMaxLinksPerGroup)) {
      tolerate([&] {
        H5L_info_t link{};
        if (H5Lget_info(obj, name.c_str(), &link, H5P_DEFAULT) < 0) return;
        // A soft link names a path that is walked through its hard links.
        if (link.type == H5L_TYPE_SOFT) return;
        if (link.type == H5L_TYPE_EXTERNAL) (void)group.external_link(name);
        // By name, as the readers open objects (a lookup, not the iteration above); an external
        // link opens its file here.
        const Id child(H5Oopen(obj, name.c_str(), H5P_DEFAULT), H5Oclose);
        if (child.valid()) object(child.get(), where.child(name), depth + 1);
      });
    }
  }

  std::set<std::string> seen_;
  std::size_t visited_ = 0;
};

[[noreturn]] void probe_in_child(const std::string& path, std::uint64_t file_bytes) {
  // A crash here is the expected outcome for a damaged file, reported by the parent.
  restore_default_crash_handlers();
  silence_error_printing();
  // The fork's copy of the parent's pages is this child's starting point.
  const std::uint64_t resident_at_start = peak_resident_bytes();
  limit_address_space_growth(probe_memory_allowance(file_bytes));
  tolerate([&] {
    const Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file.valid()) return;
    const Id root(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose);
    if (!root.valid()) return;
    Walker walker;
    walker.object(root.get(), Where{path, "/"}, 0);
  });
  const std::uint64_t grown = peak_resident_bytes() - resident_at_start;
  // No exit handlers, no stdio flush: the child shares the parent's buffers and files.
  const bool excess = walk_ran_out_of_memory || grown > probe_memory_allowance(file_bytes);
  ::_exit(excess ? kProbeExcessMemory : kProbeOk);
}

std::string describe_failure(int status, std::uint64_t file_bytes) {
  if (WIFEXITED(status) && WEXITSTATUS(status) == kProbeExcessMemory)
    return "reading the structure of this " + std::to_string(file_bytes) +
           "-byte file needed more than " +
           std::to_string(probe_memory_allowance(file_bytes) >> 20) +
           " MB of memory in a separate test process (libhdf5 sizes buffers by a damaged "
           "length field)";
  if (WIFSIGNALED(status))
    return crash_text(status) + " while a separate test process read the file's structure";
  return "the separate test process that read the file's structure with libhdf5 failed (exit "
         "status " +
         std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
}

}  // namespace

void probe_before_open(const std::string& path, const Where& where) {
  if (!open_probe_enabled()) return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;  // the open itself names the problem
  const std::string key = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino) + ":" +
                          std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) +
                          "." + std::to_string(st.st_mtim.tv_nsec);
  static std::mutex mutex;
  static std::set<std::string> probed;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (probed.count(key) != 0) return;
  }
  const pid_t child = ::fork();
  // Without a child (no process or memory left) the file is opened unprobed, as before.
  if (child < 0) return;
  const auto file_bytes = static_cast<std::uint64_t>(st.st_size);
  if (child == 0) probe_in_child(path, file_bytes);
  const double limit = kProbeBaseSeconds + static_cast<double>(st.st_size) / kProbeBytesPerSecond;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit);
  auto pause = std::chrono::microseconds(200);
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (done == child) break;
    if (done < 0 && errno != EINTR) return;  // SIGCHLD ignored: the child cannot be waited for
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(child, SIGKILL);
      while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
      }
      throw DamagedFileError(where.file, where.object, "open file",
                             "libhdf5 did not finish reading the file's structure within " +
                                 std::to_string(static_cast<long>(limit)) +
                                 " s in a separate test process (a damaged file can make it "
                                 "loop); the file was not changed");
    }
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(10'000));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != kProbeOk)
    throw DamagedFileError(where.file, where.object, "open file",
                           "damaged HDF5 file: " + describe_failure(status, file_bytes) +
                               "; this process did not open it and the file was not changed");
  const std::lock_guard<std::mutex> lock(mutex);
  // Bounded: a process that opens many files remembers only the latest ones.
  if (probed.size() >= 4096) probed.clear();
  probed.insert(key);
}

}  // namespace softevo::io::h5
