// Work that may crash libhdf5, done in a forked child process so that a crash costs an error,
// not this process: the open probe (io/open_probe.hpp) and the pack of a finished archive
// (io/archive_pack.cpp). libhdf5 1.10 crashes (SIGSEGV) on some damaged files and when the
// disk fills during an object copy (issue 29); no check of ours can run inside the library.
#pragma once

#include <sys/types.h>

#include <functional>
#include <string>

namespace softevo::io {

// In a forked child: the parent's crash handlers (Open MPI's print a backtrace) are not the
// child's business; a crash there is an expected outcome the parent reports.
void restore_default_crash_handlers();

// "libhdf5 crashed (signal 11: Segmentation fault)" for a wait status that is a signal's.
std::string crash_text(int wait_status);

// Runs `body` in a forked child that dies with this process (a SIGKILL of the parent kills it)
// and waits for it. Returns "" when the child finished; otherwise what went wrong: the message
// of the exception `body` threw, or crash_text() when the child died of a signal. `what` names
// the work in the messages ("the pack"). No fork possible: the reason, and `body` never runs.
// The child ends with _exit: no exit handlers, no stdio flush (it shares the parent's buffers).
std::string run_in_child(const std::string& what, const std::function<void()>& body);

}  // namespace softevo::io
