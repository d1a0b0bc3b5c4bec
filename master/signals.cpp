#include "master/signals.hpp"

#include <atomic>
#include <csignal>

namespace softevo::master {
namespace {

std::atomic<int> g_stop{0};
std::atomic<int> g_signal{0};  // the signal that raised g_stop last
static_assert(std::atomic<int>::is_always_lock_free, "signal handler needs a lock-free atomic");

// True if this call raised the level (the caller then names the cause).
bool raise_to(int level) {
  int cur = g_stop.load();
  while (cur < level)
    if (g_stop.compare_exchange_weak(cur, level)) return true;
  return false;
}

extern "C" void on_stop_signal(int sig) {
  if (raise_to(sig == SIGUSR1 ? static_cast<int>(StopRequest::after_generation)
                              : static_cast<int>(StopRequest::now)))
    g_signal.store(sig);
}

}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGUSR1, &sa, nullptr);
}

StopRequest stop_requested() {
  return static_cast<StopRequest>(g_stop.load());
}
const char* stop_signal_name() {
  switch (g_signal.load()) {
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGUSR1:
      return "SIGUSR1";
    default:
      return "";
  }
}
void request_stop(StopRequest r) {
  if (raise_to(static_cast<int>(r))) g_signal.store(0);
}
void clear_stop_request() {
  g_stop.store(0);
  g_signal.store(0);
}

}  // namespace softevo::master
