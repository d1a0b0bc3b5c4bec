// io/child_process.hpp: forked children for the work that may crash libhdf5.
#include "io/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <string>

#include "common/safe_write.hpp"

namespace softevo::io {

void restore_default_crash_handlers() {
  for (const int signal : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT}) {
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
  }
}

std::string crash_text(int wait_status) {
  const int signal = WTERMSIG(wait_status);
  return "libhdf5 crashed (signal " + std::to_string(signal) + ": " + ::strsignal(signal) + ")";
}

std::string run_in_child(const std::string& what, const std::function<void()>& body) {
  int message_pipe[2] = {-1, -1};
  if (::pipe2(message_pipe, O_CLOEXEC) != 0)
    return "cannot start the process for " + what + ": " + std::strerror(errno);
  const pid_t parent = ::getpid();
  const pid_t child = ::fork();
  if (child < 0) {
    const int error = errno;
    ::close(message_pipe[0]);
    ::close(message_pipe[1]);
    return "cannot start the process for " + what + ": " + std::strerror(error);
  }
  if (child == 0) {
    ::close(message_pipe[0]);
    restore_default_crash_handlers();
    // A child that outlived a killed parent would go on writing beside the next run's files.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(1);
    std::string error;
    try {
      body();
      ::_exit(0);
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = "unknown error";
    }
    if (error.empty()) error = "failed";
    write_fully(message_pipe[1], error);  // a lost message: the parent reports the exit status
    ::_exit(1);
  }
  ::close(message_pipe[1]);
  std::string message;
  char buffer[4096];
  for (;;) {
    const ssize_t got = ::read(message_pipe[0], buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;
    message.append(buffer, static_cast<std::size_t>(got));
  }
  ::close(message_pipe[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0)
    if (errno != EINTR) return "lost the process of " + what + ": " + std::strerror(errno);
  if (WIFSIGNALED(status)) return crash_text(status) + " in the separate process of " + what;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  return message.empty() ? what + " failed (exit status " +
                               std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")"
                         : message;
}

}  // namespace softevo::io
