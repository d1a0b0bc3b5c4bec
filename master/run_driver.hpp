// The console side of a run, whatever evaluates its units: the header, one progress reporter per
// run, the generation loop (master/run.hpp execute_runs) on the given executor, the summary and
// the exit code. softevo-mpi's rank 0 (master/mpi_driver.cpp) drives it with the MPI executor or,
// alone, with LocalExecutor; `softevo evolve` with the worker threads of
// master/thread_executor.hpp. MPI-free.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "master/progress.hpp"
#include "master/run.hpp"

namespace softevo::master {

struct DriverOptions {
  std::string program = "softevo-mpi";  // starts the header and the stderr lines
  std::string workers;                  // the header's "3 ranks" / "2 worker threads"
  std::string config_path;              // shown in the header
  bool quiet = false;                   // no console output (tests)
  // -q: warnings and errors only; -v: the resolved config in the header too.
  bool terse = false;
  bool verbose = false;
  ProgressMode progress = ProgressMode::automatic;  // --progress: the live line
};

// A run that completed without a single robot ok in the generations it evaluated (every one
// killed, diverged or failed: e.g. pneumatics.conductivity = 15 explodes them all) is archived
// complete but ends with this exit code and an error line, as a run whose generations all
// failed does (exit 1; issue 39: it used to exit 0).
inline constexpr int kExitNoRobotOk = 1;
// That error's text for `run` (naming its archive and the statuses), or "" when some robot of the
// generations this start evaluated was ok, or none was evaluated.
std::string no_robot_ok(const PreparedRun& run);

// Runs `runs` (prepared by prepare_run) on `executor`, printing as `options` say; returns the
// exit code: kExitRequeue if any run was interrupted, else kExitNoRobotOk if a complete run had
// no robot ok, else 0. `stop_reason` (optional) says why
// an interrupted run stopped ("" = the signal this process received). A RunError is rethrown
// with where --resume continues each run.
int drive_runs(const std::vector<PreparedRun*>& runs, UnitExecutor& executor,
               const DriverOptions& options, const std::function<std::string()>& stop_reason = {});

// What stopped this process: its launcher died, or a signal (or a stop request from code)
// arrived: "rank 0 received SIGTERM".
std::string rank0_stop_cause();

}  // namespace softevo::master
