// Stop requests from signals (Slurm's warning before the time limit, scancel, Ctrl-C).
//   SIGUSR1           -> finish the current generation, checkpoint, exit kExitRequeue;
//   SIGTERM / SIGINT  -> stop now: keep the last checkpoint (the previous generation), exit
//                        kExitRequeue. A second SIGINT/SIGTERM is just recorded again.
// The handlers only store into a lock-free atomic (async-signal-safe).
#pragma once

namespace softevo::master {

// Exit code of a run stopped by a signal after checkpointing (sysexits EX_TEMPFAIL): the Slurm
// script requeues the job on this code and the next start continues with --resume.
inline constexpr int kExitRequeue = 75;

enum class StopRequest : int { none = 0, after_generation = 1, now = 2 };

void install_stop_handlers();  // SIGTERM, SIGINT, SIGUSR1
StopRequest stop_requested();
// The signal behind the strongest stop request so far ("SIGTERM", "SIGINT", "SIGUSR1"), for the
// message that says why a run stopped; "" when none arrived (or the request came from code).
const char* stop_signal_name();
void request_stop(StopRequest r);  // for tests and the drivers (keeps the strongest request)
void clear_stop_request();         // for tests (also forgets the signal)

}  // namespace softevo::master
