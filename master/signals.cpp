#include "master/signals.hpp"

#include <atomic>
#include <csignal>

namespace softevo::master {
namespace {

std::atomic<int> g_stop{0};
static_assert(std::atomic<int>::is_always_lock_free, "signal handler needs a lock-free atomic");

void raise_to(int level) {
  int cur = g_stop.load();
  while (cur < level && !g_stop.compare_exchange_weak(cur, level)) {
  }
}

extern "C" void on_stop_signal(int sig) {
  raise_to(sig == SIGUSR1 ? static_cast<int>(StopRequest::after_generation)
                          : static_cast<int>(StopRequest::now));
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
void request_stop(StopRequest r) {
  raise_to(static_cast<int>(r));
}
void clear_stop_request() {
  g_stop.store(0);
}

}  // namespace softevo::master
