// Progress reporter: observes the generation loop (ARCHITECTURE.md section 3: reporters, not
// print statements inside the loop). One line per evaluated generation on `out`; on a terminal
// also a live line within the generation (carriage return, throttled to a few updates/s).
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace softevo::master {

struct GenerationSummary {
  std::int64_t generation = 0;
  double best = 0.0;
  double mean = 0.0;
  std::int64_t species = 0;
  std::int64_t evaluations = 0;     // work units simulated
  double eval_wall_seconds = 0.0;   // [s] evaluation phase
  double generation_seconds = 0.0;  // [s] whole generation incl. reproduction and archive
  std::int64_t reused = 0;          // work units whose result was reused (not simulated)
};

class ProgressReporter {
 public:
  // `live` = nullptr disables the live line (not a terminal, or quiet).
  // `label` starts every line (several runs in one job name their archive).
  ProgressReporter(std::FILE* out, std::FILE* live, std::int64_t total_generations,
                   std::string label = "");
  // A reporter that prints nothing.
  static ProgressReporter silent() { return ProgressReporter(nullptr, nullptr, 0); }
  // stdout for the lines, stderr for the live line if stderr is a terminal.
  static ProgressReporter console(std::int64_t total_generations);

  void generation_started(std::int64_t generation, std::size_t units_total);
  void unit_done(std::size_t units_done, std::size_t units_total);
  void generation_finished(const GenerationSummary& s);
  void message(const char* text);  // a free-form line (clears the live line first)

 private:
  void clear_live();
  std::FILE* out_;
  std::FILE* live_;
  std::string label_;
  std::int64_t total_generations_;
  std::int64_t generation_ = 0;
  std::int64_t generations_reported_ = 0;
  double seconds_reported_ = 0.0;  // sum of generation_seconds, for the ETA
  bool live_visible_ = false;
  std::chrono::steady_clock::time_point generation_start_;
  std::chrono::steady_clock::time_point last_live_;
};

// "1h02m", "3m05s", "12s"
void format_duration(double seconds, char* buf, std::size_t size);

}  // namespace softevo::master
