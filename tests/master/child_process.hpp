// Child processes for the tests that start softevo-mpi (or mpirun) for real: kill it, signal it,
// resume it. The launcher's OMPI_/PMIX_/OPAL_/ORTE_ variables of a test that runs under mpirun
// itself are removed, so a child never tries to join the test's own MPI job.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace softevo::test {

struct ChildOptions {
  std::vector<std::string> environment;  // added to the (cleaned) environment, "NAME=value"
  bool own_process_group = false;        // the child leads a new process group (kill(-pid))
};

// Starts argv[0] (a path) with stdout and stderr into `log`; -1 if it cannot be started.
inline pid_t spawn_child(const std::vector<std::string>& args, const std::string& log,
                         const ChildOptions& options = {}) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string v = *e;
    if (v.rfind("OMPI_", 0) == 0 || v.rfind("PMIX_", 0) == 0 || v.rfind("OPAL_", 0) == 0 ||
        v.rfind("ORTE_", 0) == 0)
      continue;
    env.push_back(v);
  }
  env.push_back("OMPI_ALLOW_RUN_AS_ROOT=1");
  env.push_back("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1");
  env.push_back("OMPI_MCA_rmaps_base_oversubscribe=1");
  env.insert(env.end(), options.environment.begin(), options.environment.end());
  std::vector<std::string> argv_s = args;
  std::vector<char*> argv, envp;
  for (auto& s : argv_s) argv.push_back(s.data());
  argv.push_back(nullptr);
  for (auto& s : env) envp.push_back(s.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  if (options.own_process_group) {
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attr, 0);
  }
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, &attr, argv.data(), envp.data());
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&fa);
  return rc == 0 ? pid : -1;
}

// The exit status of `child` (128 + signal if a signal ended it); waits for it.
inline int wait_exit(pid_t child, bool* signalled = nullptr) {
  int st = 0;
  waitpid(child, &st, 0);
  if (signalled != nullptr) *signalled = WIFSIGNALED(st);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

// Polls `done` every 20 ms for at most `seconds`; true once it holds.
inline bool wait_until(const std::function<bool()>& done, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

inline std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace softevo::test
