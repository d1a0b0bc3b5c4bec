#include "master/mpi_driver.hpp"

#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/launcher_watch.hpp"
#include "common/version.hpp"
#include "common/wire.hpp"
#include "master/run_driver.hpp"
#include "master/run_state.hpp"
#include "master/signals.hpp"

namespace softevo::master {
namespace {

bool same_host(const RankProcess& p) {
  return !p.host.empty() && p.host == host_name();
}

// True if process `pid` of this host has ended: gone, or a zombie its parent has not reaped.
bool process_ended(long pid) {
  std::FILE* stat = std::fopen(("/proc/" + std::to_string(pid) + "/stat").c_str(), "r");
  if (stat == nullptr) return true;
  // "pid (comm) S ...": the state follows the last ')' (comm may contain anything).
  char buf[512];
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, stat);
  std::fclose(stat);
  const std::string text(buf, n);
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos || close + 2 >= text.size()) return false;
  const char state = text[close + 2];
  return state == 'Z' || state == 'X';
}

// Why the run stops now, from this process's point of view; "" = no stop-now request. A dead
// launcher also becomes a stop request, so the loop of master/run.cpp stops too.
std::string own_stop_reason() {
  if (launcher_gone()) request_stop(StopRequest::now);
  return stop_requested() == StopRequest::now ? rank0_stop_cause() : "";
}

// Self-scheduling over ranks 1..N-1: every idle worker gets the next unit; each result frees its
// worker for the next one. Waiting = poll + sleep back-off (never a spinning core).
class MpiExecutor : public UnitExecutor {
 public:
  MpiExecutor(const mpi::Communicator& comm, std::vector<RankProcess> processes, bool quiet)
      : comm_(comm), processes_(std::move(processes)), quiet_(quiet) {
    for (int r = comm_.size() - 1; r >= 1; --r) idle_.push_back(r);
  }
  int ranks() const override { return comm_.size(); }
  // Why the run stopped now ("" if it did not): a signal, a worker that left, lost ranks.
  const std::string& stop_reason() const { return stop_reason_; }
  // Ranks whose process on this host is gone (no stop message is sent to them).
  const std::set<int>& lost() const { return lost_; }

  std::optional<std::size_t> evaluate_any(
      const std::vector<ActiveGeneration>& generations) override {
    mpi::PollBackoff backoff;
    const auto generation_of = [&](std::size_t run) -> const ActiveGeneration* {
      for (const ActiveGeneration& a : generations)
        if (a.run == run) return &a;
      return nullptr;
    };
    for (;;) {
      if (!stopping()) {
        if (std::string reason = own_stop_reason(); !reason.empty()) begin_stop(reason);
      }
      if (!stopping()) {
        // A generation may be done without a unit (every result reused) or by the last result.
        for (const ActiveGeneration& a : generations)
          if (a.scheduler->done()) return a.run;
      }
      for (const ActiveGeneration& a : generations) {
        while (!stopping() && !idle_.empty() && a.scheduler->has_next()) {
          const WorkUnit unit = *a.scheduler->next();
          const int dest = idle_.back();
          idle_.pop_back();
          busy_[dest] = a.run;
          // A send to a worker that died may never complete: a stop request ends the wait.
          std::string reason;
          if (!comm_.send_unless(dest, mpi::Tag::request, encode_eval_request(a.request(unit)),
                                 [&reason] { return !(reason = own_stop_reason()).empty(); }))
            begin_stop(reason);
        }
      }
      if (stopping() && (left_.size() + 1 == static_cast<std::size_t>(comm_.size()) ||
                         Clock::now() >= roll_call_end_)) {
        end_stop(generations.front().scheduler->generation());
        return std::nullopt;
      }
      const std::optional<mpi::Envelope> pending = comm_.poll();
      if (!pending) {
        backoff.sleep();
        continue;
      }
      backoff.reset();
      const mpi::Message message = comm_.receive(*pending);
      const std::string text(message.bytes.begin(), message.bytes.end());
      switch (message.tag) {
        case mpi::Tag::error:
          throw RunError(text);
        case mpi::Tag::leaving:
          left_.insert(message.source);
          busy_.erase(message.source);  // its unit, if any, was dropped
          if (!stopping()) begin_stop(text);
          continue;
        case mpi::Tag::result:
          break;
        default:
          throw RunError("master: unexpected message with tag " +
                         std::string(mpi::tag_name(message.tag)) + " from rank " +
                         std::to_string(message.source));
      }
      const auto busy = busy_.find(message.source);
      if (busy == busy_.end())
        throw RunError("master: a result from rank " + std::to_string(message.source) +
                       ", which has no unit");
      const std::size_t run = busy->second;
      busy_.erase(busy);
      idle_.push_back(message.source);
      if (stopping()) continue;  // after a stop-now the partial generations are discarded
      const ActiveGeneration* a = generation_of(run);
      if (a == nullptr)
        throw RunError("master: a result of run " + std::to_string(run) +
                       ", which has no generation in flight");
      EvalResult result = decode_eval_result(message.bytes);
      result.worker_rank = message.source;
      a->scheduler->complete(result);
      a->progress->unit_done(a->scheduler->units_done(), a->scheduler->units_total());
    }
  }

 private:
  using Clock = std::chrono::steady_clock;
  bool stopping() const { return !first_reason_.empty(); }

  void begin_stop(const std::string& reason) {
    first_reason_ = reason;
    roll_call_end_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(kRollCallSeconds));
  }

  // Names the lost ranks, prints the one line, and leaves the reason for the summary. A rank is
  // lost if its process on this host has ended; a rank elsewhere that sent no Tag::leaving
  // while others did after the same job-wide signal (mpirun signals every rank) is named as
  // not answering. The stop message still goes to the latter: it may just not have been
  // signalled.
  void end_stop(std::int64_t generation) {
    const bool job_wide_signal = stop_signal_name()[0] != '\0' && !left_.empty();
    std::string lost_text;
    for (int r = 1; r < comm_.size(); ++r) {
      if (left_.count(r) != 0) continue;
      const RankProcess* p =
          static_cast<std::size_t>(r) < processes_.size() ? &processes_[r] : nullptr;
      std::string why;
      if (p != nullptr && same_host(*p) && p->pid > 0 && process_ended(p->pid)) {
        why = "its process, pid " + std::to_string(p->pid) + ", is gone";
        lost_.insert(r);
      } else if (job_wide_signal) {
        why = "it did not answer the stop";
      }
      if (why.empty()) continue;
      lost_text += (lost_text.empty() ? "" : ", ") + ("rank " + std::to_string(r)) +
                   (p != nullptr && !p->host.empty() ? " on " + p->host : "") + " was lost (" +
                   why + ": killed, crashed or its node failed)";
    }
    stop_reason_ = lost_text.empty() ? first_reason_ : lost_text + ", then " + first_reason_;
    if (!quiet_) {
      std::fprintf(stderr, "softevo-mpi: stopping at once: %s; generation %lld is dropped, %s\n",
                   stop_reason_.c_str(), static_cast<long long>(generation),
                   resume_note(generation).c_str());
      std::fflush(stderr);
    }
  }

  const mpi::Communicator& comm_;
  std::vector<RankProcess> processes_;
  bool quiet_;
  std::vector<int> idle_;
  std::map<int, std::size_t> busy_;  // ranks with a unit in flight -> the unit's run
  std::set<int> left_;               // ranks that sent Tag::leaving
  std::set<int> lost_;
  std::string first_reason_;  // what started the stop
  std::string stop_reason_;   // the full reason, once stopped
  Clock::time_point roll_call_end_;
};

// How long the stop messages may take in all [s]: a worker polls every <= 10 ms, so only a dead
// one (on another host, not known as lost) takes longer, and its send would never end.
constexpr int kStopSendSeconds = 5;

// Tells every worker but the `lost` ones to return `exit_code`: the one way a worker learns it
// (mpi/protocol.hpp). A failed send to a worker that is gone without being known as lost (on
// another host) must not hide the run's outcome: it is reported and the others still get theirs.
void stop_workers(const mpi::Communicator& comm, int exit_code, const std::set<int>& lost,
                  bool quiet) {
  const std::vector<std::uint8_t> bytes = encode_shutdown(exit_code);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kStopSendSeconds);
  const auto too_late = [&deadline] { return std::chrono::steady_clock::now() > deadline; };
  for (int r = 1; r < comm.size(); ++r) {
    if (lost.count(r) != 0) continue;
    try {
      if (!comm.send_unless(r, mpi::Tag::stop, bytes, too_late) && !quiet)
        std::fprintf(stderr, "softevo-mpi: rank %d did not take its stop message within %d s\n", r,
                     kStopSendSeconds);
    } catch (const mpi::Error& e) {
      if (!quiet) std::fprintf(stderr, "softevo-mpi: %s\n", e.what());
    }
  }
}

}  // namespace

RankProcess parse_rank_process(const std::string& text) {
  RankProcess p;
  const std::size_t space = text.find(' ');
  if (space == std::string::npos || space == 0) return p;
  try {
    std::size_t used = 0;
    const long pid = std::stol(text.substr(0, space), &used);
    if (used != space || pid <= 0) return p;
    p.pid = pid;
    p.host = text.substr(space + 1);
  } catch (const std::exception&) {
  }
  return p;
}

std::string format_rank_process(long pid, const std::string& host) {
  return std::to_string(pid) + " " + host;
}

int run_master(const mpi::Communicator& comm, PreparedRun& run, const MasterOptions& options) {
  return run_master(comm, std::vector<PreparedRun*>{&run}, options);
}

int run_master(const mpi::Communicator& comm, const std::vector<PreparedRun*>& runs,
               const MasterOptions& options) {
  DriverOptions driver;
  driver.workers = std::to_string(comm.size()) + (comm.size() == 1 ? " rank" : " ranks");
  driver.config_path = options.config_path;
  driver.quiet = options.quiet;
  driver.terse = options.terse;
  driver.verbose = options.verbose;
  driver.progress = options.progress;
  int code = 0;
  std::set<int> lost;
  if (comm.size() == 1) {
    LocalExecutor local(options.evaluate_alone);
    code = drive_runs(runs, local, driver);
  } else {
    MpiExecutor executor(comm, options.processes, options.quiet);
    code = drive_runs(runs, executor, driver, [&executor] { return executor.stop_reason(); });
    lost = executor.lost();
  }
  // An orphan's workers are orphans too and leave by themselves; its MPI may be half gone.
  if (launcher_gone()) return code;
  // Last: a worker exits as soon as it has the code, and mpirun may then end the whole job.
  stop_workers(comm, code, lost, options.quiet);
  return code;
}

}  // namespace softevo::master
