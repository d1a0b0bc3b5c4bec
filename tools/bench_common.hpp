// Shared by the `softevo bench ...` subcommands: the `bench` group and the clocks they report.
#pragma once

#include <algorithm>
#include <cstdint>
#include <ctime>
#include <optional>
#include <vector>

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

// The clock this thread's core runs at [Hz], measured, or nothing on an architecture without
// the loop below. Virtual machines hide the clock and the cycle counters, yet the distance of
// the step from the core's arithmetic bound is counted in cycles (docs/scaling.md): a chain of
// dependent integer additions retires one addition per cycle on every x86-64 and AArch64 core
// (the loop's own counter runs beside it on another ALU), so additions per CPU second of this
// thread is the clock. The fastest of `samples` samples of about `seconds` each is kept: a
// sample that the host interrupted only reads lower.
inline std::optional<double> measure_core_clock_hz(double seconds = 0.05, int samples = 5) {
#if defined(__x86_64__) || defined(__aarch64__)
  constexpr int kAddsPerIteration = 8;
  std::uint64_t iterations = 1 << 16;
  std::vector<double> rates;
  std::uint64_t chain = 0;
  while (static_cast<int>(rates.size()) < samples) {
    const double t0 = thread_cpu_seconds();
    for (std::uint64_t i = 0; i < iterations; ++i) {
#if defined(__x86_64__)
      asm volatile(
          "add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\t"
          "add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0"
          : "+r"(chain));
#else
      asm volatile(
          "add %0, %0, #1\n\tadd %0, %0, #1\n\tadd %0, %0, #1\n\tadd %0, %0, #1\n\t"
          "add %0, %0, #1\n\tadd %0, %0, #1\n\tadd %0, %0, #1\n\tadd %0, %0, #1"
          : "+r"(chain));
#endif
    }
    const double elapsed = thread_cpu_seconds() - t0;
    if (elapsed < 0.5 * seconds) {  // too short to time: lengthen and try again
      iterations *= 4;
      continue;
    }
    rates.push_back(static_cast<double>(iterations) * kAddsPerIteration / elapsed);
  }
  return *std::max_element(rates.begin(), rates.end());
#else
  (void)seconds;
  (void)samples;
  return std::nullopt;
#endif
}

}  // namespace softevo::cli
