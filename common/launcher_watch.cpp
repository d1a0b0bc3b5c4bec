#include "common/launcher_watch.hpp"

#include <unistd.h>

#include <atomic>
#include <cstdlib>

namespace softevo {
namespace {

// The launcher's pid; 0 = not watched. Atomic so any thread may ask.
std::atomic<pid_t> g_launcher{0};

bool started_by_a_launcher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "SLURM_STEP_ID"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

}  // namespace

void watch_launcher() {
  if (g_launcher.load() != 0 || !started_by_a_launcher()) return;
  const pid_t parent = getppid();
  if (parent > 1) g_launcher.store(parent);  // parent 1: already an orphan, nothing to compare
}

bool launcher_gone() {
  const pid_t launcher = g_launcher.load();
  return launcher != 0 && getppid() != launcher;
}

std::string launcher_gone_reason() {
  if (!launcher_gone()) return "";
  return "its launcher (mpirun, orted or srun; pid " + std::to_string(g_launcher.load()) +
         ") is gone";
}

}  // namespace softevo
