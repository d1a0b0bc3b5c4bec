// What the state of an archive means for the user, in the words every command uses: the
// master's line when it stops, the `--resume` start and `softevo info` (docs/archive.md, "What
// survives which fault").
//
// The state attribute is written by the run itself, so a run that died without closing
// (SIGKILL of a rank or of mpirun, a node failure, a crash) leaves "running". Whether such an
// archive is still being written is decided by its run lock (io/run_lock.hpp): held = a live
// run, free = the writer died.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "io/archive.hpp"

namespace softevo::master {

// "the archive keeps generations 0-4 and --resume continues from generation 5" (or "holds no
// generation yet and --resume starts at generation 0"), for a stop while generation
// `generations_done` was in flight.
std::string resume_note(std::int64_t generations_done);

// One line on an archive whose last run did not complete, for `info` and the next start;
// nothing for a complete archive or a live run. `lock_holder`: the run lock's holder
// ("pid 4242 on node17"), nothing if the lock is free (io::lock_holder). `generations`: the
// run's run.generations if known; a run that died after archiving all of them only needs
// --resume to mark it complete.
std::optional<std::string> previous_run_note(const io::RunInfo& info,
                                             const std::optional<std::string>& lock_holder,
                                             std::optional<std::int64_t> generations = {});

}  // namespace softevo::master
