// What this process may still allocate, for the estimates that refuse a job before it runs out
// of memory halfway (issue 29: a run's population of 10^6, `softevo render` at 8192 x 8192).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace softevo {

// The smallest of: /proc/meminfo MemAvailable; a cgroup's (v1 or v2) memory limit less its
// usage; the address-space limit (ulimit -v) less this process's present address space, beyond
// which every allocation fails. nullopt when none can be read. `where` names which it is.
struct AvailableMemory {
  std::uint64_t bytes = 0;
  std::string where;
};
std::optional<AvailableMemory> available_memory();

// "12 MiB" (rounded to the nearest mebibyte).
std::string mebibytes(std::uint64_t bytes);

}  // namespace softevo
