// Shared by the `softevo bench ...` subcommands: the `bench` group and the clocks they report.
#pragma once

#include <ctime>

#include <CLI/CLI.hpp>

namespace softevo::cli {

// The `bench` group is shared by every benchmark: whoever registers first creates it.
inline CLI::App* bench_group(CLI::App& app) {
  try {
    return app.get_subcommand("bench");
  } catch (const CLI::OptionNotFound&) {
    CLI::App* bench = app.add_subcommand("bench", "benchmarks that print figures");
    bench->require_subcommand(1);
    return bench;
  }
}

// CPU seconds of the calling thread: the figure that stays meaningful on a shared machine.
inline double thread_cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Monotonic wall-clock seconds, printed next to the CPU figure.
inline double wall_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace softevo::cli
