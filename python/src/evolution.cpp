// softevo.evolve from Python: the run loop of softevo-mpi (master/run.hpp) driven one generation
// per call, its units evaluated by worker threads (master/thread_executor.hpp), so a run from
// Python writes the archive `softevo evolve` and softevo-mpi write, bit for bit. The GIL is
// released while the threads evaluate; Ctrl-C (Python's SIGINT) is seen within 50 ms and stops
// the run like softevo-mpi's SIGINT: the generation in flight is dropped, the archive keeps the
// last checkpoint and is marked interrupted, and KeyboardInterrupt reaches the caller.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "evo/genome.hpp"
#include "io/archive.hpp"
#include "master/progress.hpp"
#include "master/run.hpp"
#include "master/run_driver.hpp"
#include "master/signals.hpp"
#include "master/thread_executor.hpp"
#include "python/src/bindings.hpp"
#include "tasks/task.hpp"
#include "worker/evaluate.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace softevo::python {
namespace {

class Evolution {
 public:
  Evolution(const Config& config, const std::string& out, int workers, bool resume, bool overwrite)
      : progress_(master::ProgressReporter::to_sink(config.run.generations,
                                                    [this](const std::string& line) {
                                                      const std::lock_guard hold(lines_mutex_);
                                                      lines_.push_back(line);
                                                    })) {
    progress_.set_program("softevo.evolve");
    if (workers <= 0) workers = master::available_cores();
    if (workers > master::kMaxWorkerThreads)
      throw py::value_error("workers must be at most " + std::to_string(master::kMaxWorkerThreads) +
                            ", got " + std::to_string(workers));
    master::RunOptions options;
    options.out_path = out;
    options.names = master::OptionNames::python();
    options.program = "softevo.evolve";
    options.resume = resume;
    options.overwrite = overwrite;
    const std::filesystem::path parent = std::filesystem::path(out).parent_path();
    if (!parent.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(parent, ec);
    }
    run_ = master::prepare_run(config, options, workers + 1);
    task_ = tasks::make_task(run_.config);
    unit_options_.abandon = [] { return master::stop_requested() == master::StopRequest::now; };
    executor_ = std::make_unique<master::ThreadExecutor>(
        workers,
        [this](const EvalRequest& request) {
          return worker::evaluate(run_.config, *task_, run_.config_hash, request, unit_options_);
        },
        [this] { return python_interrupted(); });
  }

  int workers() const { return executor_->workers(); }
  // The console's lines (one per generation, with its ETA; warnings) since the last call.
  std::vector<std::string> take_lines() {
    const std::lock_guard hold(lines_mutex_);
    std::vector<std::string> lines;
    lines.swap(lines_);
    return lines;
  }
  std::string out() const { return run_.options.out_path; }
  std::int64_t generations() const { return run_.config.run.generations; }
  std::int64_t generations_done() const { return run_.info.generations_done; }
  bool resumed() const { return run_.resumed; }
  std::string state() const { return to_string(state_); }

  // Evaluates and archives the next generation; its number, or None once every generation is
  // archived (the archive is then marked complete). Raises KeyboardInterrupt after Ctrl-C
  // (the archive marked interrupted), RunError on an unrecoverable error.
  std::optional<std::int64_t> step() {
    if (closed_) return std::nullopt;
    try {
      return step_or_throw();
    } catch (const py::error_already_set&) {
      throw;  // KeyboardInterrupt, after the checkpoint
    } catch (const std::exception& e) {
      if (closed_) throw;  // the run ended first (stopped, or complete without a robot ok)
      // A failed run, as on the command line (master::execute_runs): the archive keeps its last
      // consistent generation and is marked interrupted with the smallest write there is (on a
      // full disk, no pack: it needs room for a second copy); the lock file stays, as a
      // failed run's does. close() has nothing left to do.
      if (loop_) loop_->mark_interrupted();
      state_ = io::RunState::interrupted;
      closed_ = true;
      run_.lock.reset();
      throw master::RunError(e.what());
    }
  }

 private:
  std::optional<std::int64_t> step_or_throw() {
    if (run_.already_complete) {
      // execute_run records the end of a run whose generations were all archived before.
      master::execute_run(run_, *executor_, progress_);
      return finish(io::RunState::complete);
    }
    if (!loop_) {
      loop_ = std::make_unique<master::RunLoop>(run_, executor_->ranks(), progress_);
      loop_->open();
    }
    if (loop_->finished()) {
      loop_->close(master::RunOutcome::complete);
      finish(io::RunState::complete);
      // As the command line's exit 1: the archive is complete, but no robot was ok.
      const std::string none_ok = master::no_robot_ok(run_);
      if (!none_ok.empty()) throw master::RunError(none_ok);
      return std::nullopt;
    }
    master::GenerationScheduler& scheduler = loop_->begin_generation();
    const std::int64_t g = scheduler.generation();
    master::RunLoop& loop = *loop_;
    master::ActiveGeneration active{
        0, &scheduler, [&loop](const master::WorkUnit& unit) { return loop.request(unit); },
        &progress_};
    for (;;) {
      std::optional<std::size_t> done;
      {
        const py::gil_scoped_release release;
        done = executor_->evaluate_any({active});
      }
      if (!done) {
        loop_->close(master::RunOutcome::interrupted);
        finish(io::RunState::interrupted);
        master::clear_stop_request();
        if (interrupted_) throw py::error_already_set();  // the KeyboardInterrupt
        throw master::RunError("the run was stopped");
      }
      // With controller learning, the generation's next learning round (as execute_runs).
      master::GenerationScheduler* round = loop_->continue_generation();
      if (round == nullptr) break;
      active.scheduler = round;
    }
    loop_->end_generation();
    return g;
  }

 public:
  // Generation g as archived: its statistics and best individual (the lowest id on ties) as a
  // robot, developed as `Run.genome` develops it.
  py::dict summary(std::int64_t g) const {
    const io::Archive archive(run_.options.out_path);
    const io::GenerationRecord r = archive.generation(g);
    r.check();
    std::size_t best = 0;
    py::dict counts;
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (r.fitness[i] > r.fitness[best]) best = i;
      const py::str name(to_string(static_cast<EvalStatus>(r.status[i])));
      counts[name] = (counts.contains(name) ? counts[name].cast<int>() : 0) + 1;
    }
    py::dict d;
    d["generation"] = g;
    d["best"] = r.best;
    d["mean"] = r.mean;
    d["sd"] = r.sd;
    d["species"] = r.species_count;
    py::dict metrics;  // a strategy other than NEAT (docs/model.md §8.12)
    for (const auto& [name, value] : r.strategy.metrics) metrics[py::str(name)] = value;
    d["strategy_metrics"] = metrics;
    d["individuals"] = r.size();
    d["status_counts"] = counts;
    d["eval_wall_seconds"] = r.eval_wall_seconds;
    d["fitness_unit"] = task_->fitness_unit();
    d["best_id"] = r.size() > 0 ? r.id[best] : -1;
    if (r.size() > 0) {
      // As `softevo export RUN.h5 --generation G --best` writes it: with its run's evaluation
      // settings, so that softevo.evaluate(robot) gives its archived fitness.
      const std::string name = archive.info().experiment + "_seed" +
                               std::to_string(archive.info().seed) + "_gen" + std::to_string(g) +
                               "_id" + std::to_string(r.id[best]);
      RobotFile robot =
          worker::robot_file_of(run_.config, evo::decode_genome(r.genome[best]), name);
      RobotEvaluation& evaluation = robot.evaluation.emplace();
      evaluation.config = archive.config_text();
      evaluation.run = run_.options.out_path;
      evaluation.generation = g;
      evaluation.id = r.id[best];
      evaluation.fitness = r.fitness[best];
      evaluation.status = to_string(static_cast<EvalStatus>(r.status[best]));
      d["best_robot"] = robot;
    }
    return d;
  }

  // Stops a run before its end (the iterator closed early): the archive keeps every archived
  // generation and is marked interrupted, so --resume / resume=True continues it.
  void close() {
    if (closed_ || !loop_) {
      closed_ = true;
      if (run_.lock) run_.lock->abandon();  // nothing written: a lock file it created goes
      run_.lock.reset();
      return;
    }
    loop_->close(loop_->finished() ? master::RunOutcome::complete
                                   : master::RunOutcome::interrupted);
    finish(loop_->finished() ? io::RunState::complete : io::RunState::interrupted);
  }

 private:
  std::optional<std::int64_t> finish(io::RunState state) {
    state_ = state;
    closed_ = true;
    // A clean end (complete, or stopped after a checkpoint): the lock file goes with the lock,
    // as on the command line (docs/archive.md: no .lock beside a finished archive).
    if (run_.lock) run_.lock->finish();
    run_.lock.reset();  // the run lock: another run may write the archive now
    return std::nullopt;
  }

  // Called by the scheduling thread while the GIL is released: a pending SIGINT (Ctrl-C) is
  // Python's KeyboardInterrupt, left set for step() to raise.
  bool python_interrupted() {
    if (interrupted_) return true;
    const py::gil_scoped_acquire acquire;
    if (PyErr_CheckSignals() != 0) interrupted_ = true;
    return interrupted_;
  }

  std::mutex lines_mutex_;
  std::vector<std::string> lines_;
  master::PreparedRun run_;
  std::unique_ptr<tasks::Task> task_;
  worker::EvaluateOptions unit_options_;
  master::ProgressReporter progress_;
  std::unique_ptr<master::ThreadExecutor> executor_;
  std::unique_ptr<master::RunLoop> loop_;
  io::RunState state_ = io::RunState::running;
  bool closed_ = false;
  std::atomic<bool> interrupted_{false};
};

}  // namespace

void bind_evolution(py::module_& m) {
  static py::exception<master::RunError> run_error(m, "RunError", PyExc_RuntimeError);
  run_error.attr("__doc__") =
      "A run that cannot start (the archive exists, is locked by another run or belongs to "
      "another experiment) or that failed; the archive keeps its last consistent generation.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const master::StartupError& e) {
      PyErr_SetString(run_error.ptr(), e.what());
    } catch (const master::RunError& e) {
      PyErr_SetString(run_error.ptr(), e.what());
    }
  });
  py::class_<Evolution>(m, "_Evolution",
                        "One run driven generation by generation (see "
                        "softevo.evolution).")
      .def(py::init<const Config&, const std::string&, int, bool, bool>(), "config"_a, "out"_a,
           "workers"_a, "resume"_a, "overwrite"_a)
      .def("step", &Evolution::step)
      .def("close", &Evolution::close)
      .def("summary", &Evolution::summary, "generation"_a)
      .def("take_lines", &Evolution::take_lines)
      .def_property_readonly("workers", &Evolution::workers)
      .def_property_readonly("out", &Evolution::out)
      .def_property_readonly("generations", &Evolution::generations)
      .def_property_readonly("generations_done", &Evolution::generations_done)
      .def_property_readonly("resumed", &Evolution::resumed)
      .def_property_readonly("state", &Evolution::state);
  m.def("_available_cores", &master::available_cores);
  m.attr("_max_workers") = master::kMaxWorkerThreads;
}

}  // namespace softevo::python
