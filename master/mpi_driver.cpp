#include "master/mpi_driver.hpp"

#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/version.hpp"
#include "common/wire.hpp"
#include "master/run.hpp"
#include "master/signals.hpp"
#include "worker/worker_loop.hpp"

#ifndef SOFTEVO_DEFAULT_SOURCE_DIR
#define SOFTEVO_DEFAULT_SOURCE_DIR "."
#endif

namespace softevo::master {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDefaultConfig = "configs/quickstart.toml";

struct Options {
  std::string config_path = kDefaultConfig;
  std::vector<std::string> overrides;
  std::int64_t seed = -1;
  std::int64_t generations = -1;
  std::int64_t population = -1;
  std::string out_path;
  bool resume = false;
  bool overwrite = false;
};

std::string broadcast_text(const std::string& text, int rank, MPI_Comm comm) {
  unsigned long long size = text.size();
  MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, comm);
  std::string out = rank == 0 ? text : std::string(size, '\0');
  if (size > 0) MPI_Bcast(out.data(), static_cast<int>(size), MPI_CHAR, 0, comm);
  return out;
}

[[noreturn]] void abort_run(MPI_Comm comm, int rank, const std::string& message) {
  std::fprintf(stderr, "softevo-mpi: rank %d: error: %s\n", rank, message.c_str());
  std::fflush(stderr);
  MPI_Abort(comm, 1);
  std::abort();  // MPI_Abort does not return
}

double cpu_seconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

void sleep_seconds(double s) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(s);
  ts.tv_nsec = static_cast<long>((s - static_cast<double>(ts.tv_sec)) * 1e9);
  nanosleep(&ts, nullptr);
}

// Self-scheduling over ranks 1..N-1: every idle worker gets the next unit; each result frees its
// worker for the next one. Waiting = MPI_Iprobe + nanosleep back-off (never a spinning core).
class MpiExecutor : public UnitExecutor {
 public:
  explicit MpiExecutor(MPI_Comm comm) : comm_(comm) {
    MPI_Comm_size(comm, &size_);
    for (int r = size_ - 1; r >= 1; --r) idle_.push_back(r);
  }
  int ranks() const override { return size_; }

  bool evaluate(GenerationScheduler& scheduler,
                const std::function<EvalRequest(const WorkUnit&)>& make_request,
                ProgressReporter& progress) override {
    double pause = worker::kPollMinSeconds;
    bool stopping = false;
    for (;;) {
      if (!stopping && stop_requested() == StopRequest::now) stopping = true;
      while (!stopping && !idle_.empty() && scheduler.has_next()) {
        const WorkUnit unit = *scheduler.next();
        const std::vector<std::uint8_t> bytes = encode_eval_request(make_request(unit));
        const int dest = idle_.back();
        idle_.pop_back();
        MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, dest, worker::kTagRequest,
                 comm_);
        ++in_flight_;
      }
      if (in_flight_ == 0 && (stopping || !scheduler.has_next())) return !stopping;
      int flag = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, comm_, &flag, &status);
      if (flag == 0) {
        sleep_seconds(pause);
        pause = std::min(pause * 1.5, worker::kPollMaxSeconds);
        continue;
      }
      pause = worker::kPollMinSeconds;
      const std::vector<std::uint8_t> bytes = worker::receive_bytes(comm_, status);
      if (status.MPI_TAG == worker::kTagError)
        throw RunError(std::string(bytes.begin(), bytes.end()));
      if (status.MPI_TAG != worker::kTagResult)
        throw RunError("master: unexpected message tag " + std::to_string(status.MPI_TAG) +
                       " from rank " + std::to_string(status.MPI_SOURCE));
      EvalResult result = decode_eval_result(bytes);
      result.worker_rank = status.MPI_SOURCE;
      --in_flight_;
      idle_.push_back(status.MPI_SOURCE);
      if (!stopping) {  // after a stop-now request the partial generation is discarded
        scheduler.complete(result);
        progress.unit_done(scheduler.units_done(), scheduler.units_total());
      }
    }
  }

  // Tells every worker to return `exit_code` (all ranks then exit with the same code).
  void shutdown(int exit_code) {
    WireWriter w;
    w.i32(exit_code);
    const std::vector<std::uint8_t> bytes = frame_message(MessageKind::shutdown, w.data());
    for (int r = 1; r < size_; ++r)
      MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, r, worker::kTagStop, comm_);
  }

 private:
  MPI_Comm comm_;
  int size_ = 1;
  std::vector<int> idle_;
  int in_flight_ = 0;
};

std::string resolve_config_path(const std::string& path) {
  if (path != kDefaultConfig || fs::exists(path)) return path;
  const std::string baked = std::string(SOFTEVO_DEFAULT_SOURCE_DIR) + "/" + kDefaultConfig;
  return fs::exists(baked) ? baked : path;
}

std::string default_out_path(const std::string& config_path, std::int64_t seed) {
  return "runs/" + fs::path(config_path).stem().string() + "-seed" + std::to_string(seed) + ".h5";
}

}  // namespace

int softevo_mpi_main(int argc, char** argv, MPI_Comm comm, const MpiMainHooks& hooks) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);

  Options o;
  CLI::App app{"softevo-mpi: distributed co-evolution of soft robot bodies and brains"};
  app.add_option("--config", o.config_path, "TOML config file")->capture_default_str();
  app.add_option("--seed", o.seed, "run seed (sets run.seed)");
  app.add_option("--out", o.out_path, "run archive (default runs/<config>-seed<S>.h5)");
  app.add_option("--generations", o.generations, "generations to evaluate (run.generations)");
  app.add_option("--population", o.population, "population size (neat.pop_size)");
  app.add_option("--set", o.overrides, "override a key: section.key=value (repeatable)");
  app.add_flag("--resume", o.resume,
               "continue the archive from its newest checkpoint (a new run if it does not exist)");
  app.add_flag("--overwrite", o.overwrite, "replace an existing archive");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Only rank 0 prints help or the usage error; every rank exits with the same code.
    const int code = rank == 0 ? app.exit(e) : e.get_exit_code();
    return code == 0 ? 0 : 2;
  }
  install_stop_handlers();

  // Rank 0 resolves the config and prepares the run; status 0 = ok, else text is the message.
  int status = 0;
  std::string text;
  std::optional<PreparedRun> run;
  if (rank == 0) {
    try {
      o.config_path = resolve_config_path(o.config_path);
      std::vector<std::string> overrides = o.overrides;
      if (o.seed >= 0) overrides.push_back("run.seed=" + std::to_string(o.seed));
      if (o.generations >= 0)
        overrides.push_back("run.generations=" + std::to_string(o.generations));
      if (o.population >= 0) overrides.push_back("neat.pop_size=" + std::to_string(o.population));
      const Config config = load_config(o.config_path, overrides);
      RunOptions ro;
      ro.out_path = o.out_path;
      if (ro.out_path.empty()) {
        ro.out_path = default_out_path(o.config_path, config.run.seed);
        std::error_code ec;
        fs::create_directories("runs", ec);
      }
      ro.resume = o.resume;
      ro.overwrite = o.overwrite;
      run.emplace(prepare_run(config, ro, size));
      text = run->config_text;
    } catch (const ConfigError& e) {
      status = 1;
      text = std::string("config error: ") + e.what();
    } catch (const std::exception& e) {
      status = 1;
      text = e.what();
    }
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, comm);
  text = broadcast_text(text, rank, comm);
  if (status != 0) {
    if (rank == 0) std::fprintf(stderr, "softevo-mpi: %s\n", text.c_str());
    return 2;
  }

  if (rank != 0) {
    try {
      const Config config = parse_config(text, "config from rank 0");
      const std::uint64_t hash = config_hash(config);
      worker::run_worker_loop(comm, config, hash, hooks.unit_options);
      // The stop message carries the exit code of the run; run_worker_loop consumed it, so the
      // workers use the code broadcast at the very end.
    } catch (const std::exception& e) {
      abort_run(comm, rank, e.what());
    }
    int code = 0;
    MPI_Bcast(&code, 1, MPI_INT, 0, comm);
    return code;
  }

  PreparedRun& r = *run;
  if (!hooks.quiet) {
    std::printf("softevo-mpi %s (commit %s), %d rank%s\n", kVersion, kGitCommit, size,
                size == 1 ? "" : "s");
    std::printf("# config %s (hash %s)\n%s", o.config_path.c_str(), hash_hex(r.config_hash).c_str(),
                r.config_text.c_str());
    std::printf("# archive %s (%s)\n", r.options.out_path.c_str(),
                r.already_complete ? "complete: nothing to do"
                : r.resumed
                    ? ("resuming at generation " + std::to_string(r.info.generations_done)).c_str()
                    : "new run");
    std::fflush(stdout);
  }
  ProgressReporter progress = hooks.quiet ? ProgressReporter::silent()
                                          : ProgressReporter::console(r.config.run.generations);
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_seconds();
  RunOutcome outcome = RunOutcome::complete;
  std::int64_t evaluations_before = 0;
  try {
    if (size == 1) {
      const worker::UnitOptions unit_options = hooks.unit_options;
      LocalExecutor local([&](const EvalRequest& req) {
        return worker::evaluate_unit(r.config, r.config_hash, req, unit_options);
      });
      outcome = execute_run(r, local, progress);
    } else {
      MpiExecutor executor(comm);
      try {
        outcome = execute_run(r, executor, progress);
      } catch (const std::exception& e) {
        abort_run(comm, 0, e.what());
      }
      executor.shutdown(outcome == RunOutcome::interrupted ? kExitRequeue : 0);
    }
  } catch (const std::exception& e) {
    abort_run(comm, 0, e.what());
  }
  (void)evaluations_before;
  const int code = outcome == RunOutcome::interrupted ? kExitRequeue : 0;
  if (!hooks.quiet) {
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = cpu_seconds() - cpu0;
    if (outcome == RunOutcome::interrupted)
      std::printf(
          "# interrupted by a signal after generation %lld; archive %s is consistent; "
          "exit %d (rerun with --resume)\n",
          static_cast<long long>(r.info.generations_done) - 1, r.options.out_path.c_str(), code);
    else if (outcome == RunOutcome::complete)
      std::printf(
          "# complete: %lld generations, archive %s; master wall %.1f s, master CPU %.2f s "
          "(%.1f%%)\n",
          static_cast<long long>(r.info.generations_done), r.options.out_path.c_str(), wall, cpu,
          wall > 0 ? 100.0 * cpu / wall : 0.0);
    std::fflush(stdout);
  }
  int bcast_code = code;
  MPI_Bcast(&bcast_code, 1, MPI_INT, 0, comm);
  return code;
}

}  // namespace softevo::master
