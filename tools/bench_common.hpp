// Shared by the `softevo bench ...` subcommands: the `bench` group and the clocks they report.
#pragma once

#include <sched.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <istream>
#include <optional>
#include <string>
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
// the step from the core's arithmetic bound is counted in cycles (docs/scaling.md). The loop is
// a chain of dependent register-register additions (`add reg, reg`; AArch64 `add xd, xd, xm`):
// each needs the previous sum, which no renamer knows, so each takes the ALU latency of one
// cycle on every x86-64 core in the uops.info and Agner Fog tables (Intel from Core 2 to Golden
// Cove and Gracemont, AMD from K8 to Zen 5) and on every AArch64 core whose optimisation guide
// lists it (Cortex-A53 to X4, Neoverse N1/N2/V1/V2, Apple). An immediate addend is not safe:
// Golden Cove-class cores fold chains of `add reg, imm` at rename and ran such a chain at
// "10 GHz" (issue 39). The fastest of `samples` samples of about `seconds` each is kept: a
// sample that the host interrupted only reads lower.
inline std::optional<double> measure_core_clock_hz(double seconds = 0.05, int samples = 5) {
#if defined(__x86_64__) || defined(__aarch64__)
  constexpr int kAddsPerIteration = 8;
  std::uint64_t iterations = 1 << 16;
  std::vector<double> rates;
  std::uint64_t chain = 0;
  // The addend lives in a register whose value the compiler does not know at the asm.
  volatile std::uint64_t addend_source = 1;
  const std::uint64_t addend = addend_source;
  while (static_cast<int>(rates.size()) < samples) {
    const double t0 = thread_cpu_seconds();
    for (std::uint64_t i = 0; i < iterations; ++i) {
#if defined(__x86_64__)
      asm volatile(
          "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\t"
          "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0"
          : "+r"(chain)
          : "r"(addend));
#else
      asm volatile(
          "add %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\t"
          "add %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1"
          : "+r"(chain)
          : "r"(addend));
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

// The clock [Hz] that /proc/cpuinfo gives for logical CPU `cpu` ("cpu MHz" of its "processor"
// block), or nothing when the text has no such figure (AArch64 kernels print none).
inline std::optional<double> cpuinfo_clock_hz(std::istream& cpuinfo, int cpu) {
  std::string line;
  int current = -1;
  while (std::getline(cpuinfo, line)) {
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon);
    key.erase(key.find_last_not_of(" \t") + 1);
    const char* value = line.c_str() + colon + 1;
    char* end = nullptr;
    if (key == "processor") {
      const long n = std::strtol(value, &end, 10);
      current = end == value ? -1 : static_cast<int>(n);
    } else if (key == "cpu MHz" && current == cpu) {
      const double mhz = std::strtod(value, &end);
      if (end != value && std::isfinite(mhz) && mhz > 0.0) return mhz * 1e6;
    }
  }
  return std::nullopt;
}

// What the operating system says this thread's core runs at [Hz], for a cross-check of the
// measured clock: cpufreq's current frequency where the kernel has it, else /proc/cpuinfo.
// Neither is the clock itself on a VM (often the nominal or the TSC rate), hence a cross-check.
inline std::optional<double> os_core_clock_hz() {
  const int cpu = ::sched_getcpu();
  if (cpu < 0) return std::nullopt;
  std::ifstream cpufreq("/sys/devices/system/cpu/cpu" + std::to_string(cpu) +
                        "/cpufreq/scaling_cur_freq");
  double khz = 0.0;
  if (cpufreq >> khz && khz > 0.0) return khz * 1e3;
  std::ifstream cpuinfo("/proc/cpuinfo");
  return cpuinfo ? cpuinfo_clock_hz(cpuinfo, cpu) : std::nullopt;
}

}  // namespace softevo::cli
