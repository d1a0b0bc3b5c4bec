#include "common/available_memory.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>

namespace softevo {
namespace {

// The first number of the file at `path` (bytes), nullopt if unreadable or "max".
std::optional<std::uint64_t> read_bytes_file(const std::string& path) {
  std::ifstream in(path);
  unsigned long long v = 0;
  if (!(in >> v)) return std::nullopt;
  return static_cast<std::uint64_t>(v);
}

// The cgroup's memory limit minus its usage, for the memory controller's path in
// /proc/self/cgroup (v2: "0::/p", v1: "N:memory:/p"); nullopt when there is no limit.
std::optional<std::uint64_t> cgroup_memory_left() {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  // Limits at or above this are "no limit" (cgroup v1 writes one near 2^63).
  constexpr std::uint64_t kUnlimited = std::uint64_t{1} << 60;
  while (std::getline(in, line)) {
    const std::size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
    std::optional<std::uint64_t> limit, used;
    if (controllers.empty()) {
      limit = read_bytes_file("/sys/fs/cgroup" + path + "/memory.max");
      used = read_bytes_file("/sys/fs/cgroup" + path + "/memory.current");
    } else if (controllers == "memory") {
      for (const std::string& dir :
           {"/sys/fs/cgroup/memory" + path, std::string("/sys/fs/cgroup/memory")}) {
        limit = read_bytes_file(dir + "/memory.limit_in_bytes");
        used = read_bytes_file(dir + "/memory.usage_in_bytes");
        if (limit) break;
      }
    }
    if (limit && *limit < kUnlimited) return *limit - std::min(*limit, used.value_or(0));
  }
  return std::nullopt;
}

// RLIMIT_AS less the address space this process has mapped (/proc/self/statm, pages); nullopt
// without a limit.
std::optional<std::uint64_t> address_space_left() {
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  std::ifstream in("/proc/self/statm");
  std::uint64_t pages = 0;
  if (!(in >> pages)) return std::nullopt;
  const std::uint64_t mapped = pages * static_cast<std::uint64_t>(::getpagesize());
  const auto cap = static_cast<std::uint64_t>(limit.rlim_cur);
  return cap - std::min(cap, mapped);
}

}  // namespace

std::optional<AvailableMemory> available_memory() {
  std::optional<AvailableMemory> best;
  const auto consider = [&](std::optional<std::uint64_t> bytes, const char* where) {
    if (bytes && (!best || *bytes < best->bytes)) best = AvailableMemory{*bytes, where};
  };
  std::ifstream in("/proc/meminfo");
  std::string key;
  unsigned long long kb = 0;
  std::string unit;
  while (in >> key >> kb >> unit)
    if (key == "MemAvailable:")
      consider(static_cast<std::uint64_t>(kb) * 1024, "MemAvailable in /proc/meminfo");
  consider(cgroup_memory_left(), "the cgroup's memory limit");
  consider(address_space_left(), "the address-space limit, ulimit -v");
  return best;
}

std::string mebibytes(std::uint64_t bytes) {
  return std::to_string((bytes + (std::uint64_t{1} << 19)) >> 20) + " MiB";
}

}  // namespace softevo
