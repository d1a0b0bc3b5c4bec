// Resource checks before a run starts (master/run.hpp): the memory of rank 0 and the open file
// descriptors of a job.
#include <sys/resource.h>

#include <algorithm>
#include <filesystem>

#include "master/run.hpp"

namespace softevo::master {

namespace {

// The descriptors this process has open now (its own, MPI's, libraries'); 0 if unknown.
std::size_t open_descriptors() {
  std::error_code ec;
  std::size_t n = 0;
  for (auto it = std::filesystem::directory_iterator("/proc/self/fd", ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec))
    ++n;
  return ec ? 0 : n;
}

}  // namespace

std::uint64_t estimate_run_memory(const Config& config) {
  const auto pop = static_cast<std::uint64_t>(std::max<std::int64_t>(config.neat.pop_size, 0));
  // Every species keeps at least max(min_species_size, elitism) members (docs/model.md §8.5). The
  // per-member figure was measured at the default 2, so only a larger minimum adds members: up
  // to (minimum - 2) more for each of at most pop/2 species of 2 (issue 39: min_species_size
  // grew a population of 4 by 300 MB/s and was not counted here).
  const auto minimum = static_cast<std::uint64_t>(
      std::max<std::int64_t>({config.neat.min_species_size, config.neat.elitism, 2}));
  const std::uint64_t members = pop + pop / 2 * (minimum - 2);
  std::uint64_t per_member = kBytesPerMember;
  if (config.learning.method != LearningMethod::none)
    per_member += kBytesPerLearningCandidate *
                  static_cast<std::uint64_t>(std::max<std::int64_t>(config.learning.population, 0));
  // MAP-Elites holds its map beside the batch: at most one elite (a member's genome) per
  // cell, and no more elites than robots the run evaluates (docs/model.md §8.12.2); unmeasured,
  // an elite taken as a member.
  std::uint64_t elites = 0;
  if (config.search.strategy == SearchKind::map_elites)
    elites = std::min(
        static_cast<std::uint64_t>(std::max<std::int64_t>(config.map_elites.max_cells, 0)),
        members * static_cast<std::uint64_t>(std::max<std::int64_t>(config.run.generations, 1)));
  // AFPO evaluates its survivors and as many new robots each generation: 2 pop_size members.
  if (config.search.strategy == SearchKind::afpo) elites = pop;
  return kRunBaseBytes + members * per_member + elites * kBytesPerMember;
}

std::string check_run_memory(const std::vector<const Config*>& configs,
                             const std::optional<AvailableMemory>& available) {
  if (!available || configs.empty()) return "";
  std::uint64_t total = 0;
  for (const Config* c : configs) total += estimate_run_memory(*c);
  const Config& first = *configs.front();
  std::string what = configs.size() == 1
                         ? "the run (neat.pop_size = " + std::to_string(first.neat.pop_size)
                         : std::to_string(configs.size()) + " runs of this job (neat.pop_size = " +
                               std::to_string(first.neat.pop_size) + " in the first";
  if (first.learning.method != LearningMethod::none)
    what += ", learning.population = " + std::to_string(first.learning.population);
  what += ")";
  const std::string keys =
      "lower neat.pop_size (--population)" +
      std::string(first.learning.method != LearningMethod::none ? " or learning.population" : "") +
      (configs.size() > 1 ? ", or run fewer seeds per job" : "");
  if (total > available->bytes)
    throw StartupError(what + " needs about " + mebibytes(total) + " of memory on rank 0, but " +
                       mebibytes(available->bytes) + " are available (" + available->where +
                       "): " + keys + "; nothing was written");
  if (total > available->bytes / 4 * 3)
    return what + " needs about " + mebibytes(total) + " of memory on rank 0, close to the " +
           mebibytes(available->bytes) + " available (" + available->where + "); if it runs out, " +
           keys;
  return "";
}

std::size_t descriptors_for_runs(std::size_t runs) {
  return open_descriptors() + runs + kDescriptorsBesideRunLocks;
}

void reserve_descriptors(std::size_t runs) {
  const std::size_t needed = descriptors_for_runs(runs);
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return;  // unknown: the opens will say
  const auto fits = [needed](rlim_t l) { return l == RLIM_INFINITY || l >= needed; };
  if (fits(limit.rlim_cur)) return;
  if (fits(limit.rlim_max)) {
    // The soft limit is this process's to raise up to the hard one: no need to ask the user.
    limit.rlim_cur = static_cast<rlim_t>(needed);
    if (::setrlimit(RLIMIT_NOFILE, &limit) == 0) return;
  }
  throw StartupError(
      std::to_string(runs) + " runs in one job need about " + std::to_string(needed) +
      " open file descriptors (one run lock each for the whole job, plus " +
      std::to_string(needed - runs) +
      " for this process, the archives being written and MPI), "
      "but the limit is " +
      std::to_string(limit.rlim_cur) + " (hard limit " +
      (limit.rlim_max == RLIM_INFINITY ? std::string("unlimited")
                                       : std::to_string(limit.rlim_max)) +
      "): raise it (ulimit -n " + std::to_string(needed) +
      " in the job script) or split the seeds over several jobs; nothing was written");
}

}  // namespace softevo::master
