#include "master/progress.hpp"

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <utility>

namespace softevo::master {

void format_duration(double seconds, char* buf, std::size_t size) {
  if (!std::isfinite(seconds) || seconds < 0) {
    std::snprintf(buf, size, "?");
    return;
  }
  const auto s = static_cast<long long>(std::llround(seconds));
  if (s >= 3600)
    std::snprintf(buf, size, "%lldh%02lldm", s / 3600, (s % 3600) / 60);
  else if (s >= 60)
    std::snprintf(buf, size, "%lldm%02llds", s / 60, s % 60);
  else
    std::snprintf(buf, size, "%llds", s);
}

namespace {

// The short status names of a generation line, in EvalStatus order.
constexpr std::array<const char*, kStatusKinds> kStatusShort = {
    "ok", "flipped", "exploded", "diverged", "failed", "timeout", "invalid body"};
// Statuses always shown (the thesis' kill rules and failures); the rest when they occur.
constexpr std::size_t kAlwaysShown = static_cast<std::size_t>(EvalStatus::failed) + 1;

std::string duration_text(double seconds) {
  char buf[32];
  format_duration(seconds, buf, sizeof buf);
  return buf;
}

}  // namespace

std::string status_counts_text(const StatusCounts& counts) {
  std::string out;
  for (std::size_t k = 0; k < kStatusKinds; ++k) {
    if (k >= kAlwaysShown && counts[k] == 0) continue;
    out +=
        (out.empty() ? "" : ", ") + std::string(kStatusShort[k]) + " " + std::to_string(counts[k]);
  }
  return out;
}

std::string generation_line(const GenerationSummary& s, std::int64_t total_generations,
                            double elapsed_seconds, double eta_seconds) {
  const double rate =
      s.eval_wall_seconds > 0 ? static_cast<double>(s.evaluations) / s.eval_wall_seconds : 0.0;
  const std::string unit = s.fitness_unit.empty() ? "" : " " + s.fitness_unit;
  char head[160];
  std::snprintf(head, sizeof head, "gen %6lld/%lld  best %10.4f%s  mean %10.4f%s  ",
                static_cast<long long>(s.generation), static_cast<long long>(total_generations),
                s.best, unit.c_str(), s.mean, unit.c_str());
  char species[32];
  std::snprintf(species, sizeof species, "species %3lld", static_cast<long long>(s.species));
  char tail[256];
  std::snprintf(tail, sizeof tail, "  %s  eval/s %7.2f  elapsed %s  ETA %s",
                s.search.empty() ? species : s.search.c_str(), rate,
                duration_text(elapsed_seconds).c_str(), duration_text(eta_seconds).c_str());
  const std::string reused = s.reused > 0 ? "  reused " + std::to_string(s.reused) : "";
  std::string learned;
  if (s.learned_bodies > 0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "  learned %lld x %lld it, gain mean %+.4f%s best %+.4f%s",
                  static_cast<long long>(s.learned_bodies),
                  static_cast<long long>(s.learning_iterations), s.learning_gain_mean, unit.c_str(),
                  s.learning_gain_best, unit.c_str());
    learned = buf;
  }
  return head + status_counts_text(s.status_counts) + tail + reused + learned;
}

std::string generation_warning(const GenerationSummary& s) {
  std::int64_t genomes = 0;
  for (const std::int64_t n : s.status_counts) genomes += n;
  const std::int64_t ok = s.status_counts[static_cast<std::size_t>(EvalStatus::ok)];
  const std::string g = "generation " + std::to_string(s.generation);
  if (genomes == 0) return "";
  if (ok == 0)
    return g + ": all " + std::to_string(genomes) + " robots were killed (" +
           status_counts_text(s.status_counts) + "): best and mean are 0 by rule, not measured";
  if (s.max_abs_ok_fitness == 0.0)
    return g + ": none of the " + std::to_string(ok) +
           " robots that finished moved (every fitness is exactly 0" +
           (s.fitness_unit.empty() ? "" : " " + s.fitness_unit) + ")";
  return "";
}

std::optional<ProgressMode> parse_progress_mode(const std::string& text) {
  if (text == "auto") return ProgressMode::automatic;
  if (text == "always") return ProgressMode::always;
  if (text == "never") return ProgressMode::never;
  return std::nullopt;
}

StreamKind stream_kind(int fd) {
  if (::isatty(fd) != 0) return StreamKind::terminal;
  struct stat st {};
  if (::fstat(fd, &st) == 0 && (S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode)))
    return StreamKind::pipe;
  return StreamKind::other;
}

namespace {

pid_t parent_of(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  // "pid (comm) state ppid ...": comm may hold spaces and parentheses, so after the last ')'.
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream rest(text.substr(close + 1));
  std::string state;
  long long ppid = 0;
  rest >> state >> ppid;
  return static_cast<pid_t>(ppid);
}

// Linux's terminal character devices: pseudo-terminals (majors 136-143), virtual consoles and
// serial lines (4), /dev/tty and /dev/console (5). /dev/null (1) is no person.
bool is_terminal_device(dev_t device) {
  const unsigned m = major(device);
  return m == 4 || m == 5 || (m >= 136 && m <= 143);
}

}  // namespace

StreamKind forwarded_stream_kind(int fd) {
  const StreamKind kind = stream_kind(fd);
  if (kind != StreamKind::pipe) return kind;
  pid_t pid = ::getppid();
  // A few levels: mpirun itself, or orted/prted and the mpirun above it.
  for (int level = 0; level < 4 && pid > 1; ++level) {
    struct stat st {};
    const std::string path = "/proc/" + std::to_string(pid) + "/fd/" + std::to_string(fd);
    if (::stat(path.c_str(), &st) != 0) return StreamKind::pipe;
    if (S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode)) {
      pid = parent_of(pid);
      continue;
    }
    return S_ISCHR(st.st_mode) && is_terminal_device(st.st_rdev) ? StreamKind::terminal
                                                                 : StreamKind::other;
  }
  return StreamKind::pipe;
}

bool show_live_line(ProgressMode mode, StreamKind stderr_kind,
                    const std::function<const char*(const char*)>& env) {
  if (mode != ProgressMode::automatic) return mode == ProgressMode::always;
  if (stderr_kind == StreamKind::terminal) return true;
  if (stderr_kind != StreamKind::pipe) return false;  // a file: a log, not a person
  const auto is = [&env](const char* name, const char* value) {
    const char* v = env(name);
    return v != nullptr && std::strcmp(v, value) == 0;
  };
  if (is("ENVIRONMENT", "BATCH") || is("PBS_ENVIRONMENT", "PBS_BATCH")) return false;
  for (const char* launcher : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "SLURM_STEP_ID"})
    if (env(launcher) != nullptr) return true;
  return false;
}

ProgressReporter::ProgressReporter(std::FILE* out, std::FILE* live, std::FILE* warn,
                                   std::int64_t total_generations, std::string label)
    : out_(out),
      live_(live),
      warn_(warn),
      label_(std::move(label)),
      total_generations_(total_generations),
      start_(std::chrono::steady_clock::now()) {}

namespace {

// The launcher's variables as the process was started with them: read during static
// initialisation, before main and so before MPI_Init, which sets OMPI_COMM_WORLD_SIZE in a
// singleton (no mpirun) as well.
std::map<std::string, std::string> launch_environment() {
  std::map<std::string, std::string> vars;
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "SLURM_STEP_ID",
                           "ENVIRONMENT", "PBS_ENVIRONMENT"})
    if (const char* v = std::getenv(name)) vars[name] = v;
  return vars;
}
const std::map<std::string, std::string> kLaunchEnvironment = launch_environment();

}  // namespace

ProgressReporter ProgressReporter::to_sink(std::int64_t total_generations,
                                           std::function<void(const std::string&)> sink) {
  ProgressReporter reporter(nullptr, nullptr, nullptr, total_generations);
  reporter.sink_ = std::move(sink);
  return reporter;
}

ProgressReporter ProgressReporter::console(std::int64_t total_generations, ProgressMode mode,
                                           bool quiet, std::string label) {
  const auto env = [](const char* name) -> const char* {
    const auto it = kLaunchEnvironment.find(name);
    return it == kLaunchEnvironment.end() ? nullptr : it->second.c_str();
  };
  // Under a launcher (a launcher variable set), a pipe is judged by where the launcher sends
  // it; any other pipe (`| tee log`) stays a pipe, which auto never decorates.
  StreamKind kind = stream_kind(STDERR_FILENO);
  if (kind == StreamKind::pipe && mode == ProgressMode::automatic &&
      show_live_line(mode, kind, env))
    kind = forwarded_stream_kind(STDERR_FILENO);
  const bool live = !quiet && show_live_line(mode, kind, env);
  return ProgressReporter(quiet ? nullptr : stdout, live ? stderr : nullptr, stderr,
                          total_generations, std::move(label));
}

void ProgressReporter::clear_live() {
  if (live_ != nullptr && live_visible_) {
    std::fprintf(live_, "\r\033[K");
    std::fflush(live_);
    live_visible_ = false;
  }
}

void ProgressReporter::generation_started(std::int64_t generation, std::size_t units_total) {
  generation_ = generation;
  round_.reset();
  generation_start_ = std::chrono::steady_clock::now();
  last_live_ = generation_start_;
  unit_done(0, units_total);
}

void ProgressReporter::unit_done(std::size_t units_done, std::size_t units_total) {
  if (live_ == nullptr) return;
  const auto now = std::chrono::steady_clock::now();
  // Throttle: at most ~5 updates per second, but always show the first and the last unit.
  if (units_done != 0 && units_done != units_total &&
      now - last_live_ < std::chrono::milliseconds(200))
    return;
  last_live_ = now;
  const double elapsed =
      std::chrono::duration<double>(now - (round_ ? round_start_ : generation_start_)).count();
  const double rate = elapsed > 0 ? static_cast<double>(units_done) / elapsed : 0.0;
  if (round_)
    std::fprintf(live_,
                 "\r\033[K  gen %lld learn %lld/%lld (%zu bodies): %zu/%zu evaluations, %.2f "
                 "eval/s, gain mean %+.4g best %+.4g",
                 static_cast<long long>(generation_), static_cast<long long>(round_->iteration),
                 static_cast<long long>(round_->iterations), round_->bodies, units_done,
                 units_total, rate, round_->gain_mean, round_->gain_best);
  else
    std::fprintf(live_, "\r\033[K  gen %lld: %zu/%zu evaluations, %.2f eval/s",
                 static_cast<long long>(generation_), units_done, units_total, rate);
  std::fflush(live_);
  live_visible_ = true;
}

void ProgressReporter::learning_started(const LearningProgress& round) {
  round_ = round;
  round_start_ = std::chrono::steady_clock::now();
  last_live_ = round_start_;
}

void ProgressReporter::generation_finished(const GenerationSummary& s) {
  clear_live();
  ++generations_reported_;
  seconds_reported_ += s.generation_seconds;
  const std::int64_t remaining = total_generations_ - (s.generation + 1);
  const double eta = static_cast<double>(remaining) * seconds_reported_ /
                     static_cast<double>(generations_reported_);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (out_ != nullptr || sink_) {
    const std::string line = label_ + generation_line(s, total_generations_, elapsed, eta);
    if (sink_) sink_(line);
    if (out_ != nullptr) {
      std::fprintf(out_, "%s\n", line.c_str());
      std::fflush(out_);
    }
  }
  const std::string warning = generation_warning(s);
  if (sink_ && !warning.empty()) sink_(program_ + ": warning: " + label_ + warning);
  if (warn_ != nullptr && !warning.empty()) {
    std::fprintf(warn_, "%s: warning: %s%s\n", program_.c_str(), label_.c_str(), warning.c_str());
    std::fflush(warn_);
  }
}

void ProgressReporter::message(const char* text) {
  clear_live();
  if (out_ == nullptr) return;
  std::fprintf(out_, "%s\n", text);
  std::fflush(out_);
}

}  // namespace softevo::master
