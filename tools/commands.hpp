// Subcommands of the single-process CLI `softevo`. Each lives in its own cmd_*.cpp and adds
// itself to the app; softevo_main.cpp calls every register function. A subcommand's callback
// stores its exit code in `exit_code`; an exception escaping it is printed by main (exit 2).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "tools/cli_checks.hpp"

namespace softevo::cli {

// Shared exit codes of the CLI tools.
inline constexpr int kExitOk = 0;
inline constexpr int kExitMismatch = 1;  // a check ran and found a difference
inline constexpr int kExitUsage = 2;     // bad arguments, unreadable or malformed input

// Bit-identical doubles (how the determinism checks of replay and the benchmarks compare
// fitness: NaN equals a NaN of the same bits, +0 differs from -0).
inline bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// A number option that must be finite and within [lo, hi]: CLI11's Range lets NaN through (it
// fails no comparison), and `render --fps nan` then wrote "-2147483647 frames".
inline CLI::Validator finite_in(double lo, double hi) {
  const std::string allowed =
      "a finite number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, allowed](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
          return text + " is not " + allowed;
        return "";
      },
      "FINITE in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

// --seconds of eval, render and view: simulated time, one type and one range everywhere, that
// of the key it sets (task.eval_seconds: more than 0, at most 3600), checked before anything is
// loaded and named like the config's own range errors.
inline CLI::Option* add_seconds_option(CLI::App& cmd, std::optional<double>& seconds,
                                       const std::string& what) {
  const CLI::Validator in_range(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v <= 0 || v > 3600)
          return "task.eval_seconds = " + text + " is out of range (more than 0, at most 3600 s)";
        return "";
      },
      "FLOAT in (0, 3600]");
  return cmd.add_option("--seconds", seconds, what + " (task.eval_seconds, default 10)")
      ->type_name("FLOAT")
      ->check(in_range);
}

// The sample robots of the repository (robots/, robots/README.md): `champions` and `bench eval`
// read them by default, from the working directory, else from the source tree the program was
// built from.
inline std::string sample_robots_dir() {
  if (std::filesystem::is_directory("robots")) return "robots";
#ifdef SOFTEVO_DEFAULT_SOURCE_DIR
  const std::string built = std::string(SOFTEVO_DEFAULT_SOURCE_DIR) + "/robots";
  if (std::filesystem::is_directory(built)) return built;
#endif
  return "robots";
}

// The subcommand `word` is closest to (common/closest_word.hpp), "" when none is: what
// "unknown command 'infoo', did you mean info?" suggests.
std::string closest_subcommand(const CLI::App& app, const std::string& word);
bool is_subcommand(const CLI::App& app, const std::string& word);

void register_version(CLI::App& app, int& exit_code);
void register_config(CLI::App& app, int& exit_code);
void register_bench_physics(CLI::App& app, int& exit_code);
void register_bench_xor(CLI::App& app, int& exit_code);
void register_develop(CLI::App& app, int& exit_code);
void register_render(CLI::App& app, int& exit_code);
void register_replay(CLI::App& app, int& exit_code);
void register_eval(CLI::App& app, int& exit_code);
void register_champions(CLI::App& app, int& exit_code);
void register_bench_eval(CLI::App& app, int& exit_code);
void register_info(CLI::App& app, int& exit_code);
void register_export(CLI::App& app, int& exit_code);
void register_fabricate(CLI::App& app, int& exit_code);
void register_repair(CLI::App& app, int& exit_code);
void register_evolve(CLI::App& app, int& exit_code);
// Registered only in a build with the viewer (SOFTEVO_ENABLE_VIEW).
void register_view(CLI::App& app, int& exit_code);

}  // namespace softevo::cli
