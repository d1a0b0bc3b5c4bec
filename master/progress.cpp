#include "master/progress.hpp"

#include <unistd.h>

#include <cmath>
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

ProgressReporter::ProgressReporter(std::FILE* out, std::FILE* live, std::int64_t total_generations,
                                   std::string label)
    : out_(out), live_(live), label_(std::move(label)), total_generations_(total_generations) {}

ProgressReporter ProgressReporter::console(std::int64_t total_generations) {
  return ProgressReporter(stdout, ::isatty(STDERR_FILENO) != 0 ? stderr : nullptr,
                          total_generations);
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
  const double elapsed = std::chrono::duration<double>(now - generation_start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(units_done) / elapsed : 0.0;
  std::fprintf(live_, "\r\033[K  gen %lld: %zu/%zu evaluations, %.2f eval/s",
               static_cast<long long>(generation_), units_done, units_total, rate);
  std::fflush(live_);
  live_visible_ = true;
}

void ProgressReporter::generation_finished(const GenerationSummary& s) {
  clear_live();
  ++generations_reported_;
  seconds_reported_ += s.generation_seconds;
  if (out_ == nullptr) return;
  const double rate =
      s.eval_wall_seconds > 0 ? static_cast<double>(s.evaluations) / s.eval_wall_seconds : 0.0;
  const std::int64_t remaining = total_generations_ - (s.generation + 1);
  char eta[32];
  format_duration(static_cast<double>(remaining) * seconds_reported_ /
                      static_cast<double>(generations_reported_),
                  eta, sizeof eta);
  char reused[48] = "";
  if (s.reused > 0)
    std::snprintf(reused, sizeof reused, "  reused %lld", static_cast<long long>(s.reused));
  std::fprintf(
      out_, "%sgen %6lld/%lld  best %10.4f  mean %10.4f  species %3lld  eval/s %7.2f  ETA %s%s\n",
      label_.c_str(), static_cast<long long>(s.generation),
      static_cast<long long>(total_generations_), s.best, s.mean, static_cast<long long>(s.species),
      rate, eta, reused);
  std::fflush(out_);
}

void ProgressReporter::message(const char* text) {
  clear_live();
  if (out_ == nullptr) return;
  std::fprintf(out_, "%s\n", text);
  std::fflush(out_);
}

}  // namespace softevo::master
