// libFuzzer target: the run-archive reader (io/archive, master/archive_check) on an arbitrary
// file, as `softevo info` and `--resume` read it. Every reader entry runs once, each on its own,
// so that a damaged section does not hide the sections after it: info, config, the generation
// list, every generation and its stored digest, stats and checkpoint; then the integrity checks
// (master/archive_check: config text, rules, the checkpoint's population). A reader may only
// fail with ArchiveError; any other exception, a crash, an allocation beyond the file's size or
// a hang is a finding.
//
// Speed (each input is a real HDF5 file, opened by libhdf5): every entry runs once, not again
// through fitness_digest and content_digest as before (they call the same entries on the same
// bytes and only hash what they get), and the input goes to one file in /dev/shm.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "io/archive.hpp"
#include "io/open_probe.hpp"
#include "master/archive_check.hpp"

namespace {

// One file per process, in memory when /dev/shm exists.
const std::string& scratch_path() {
  static const std::string path = [] {
    const std::filesystem::path dir =
        std::filesystem::exists("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    return (dir / ("softevo-fuzz-archive-" + std::to_string(::getpid()) + ".h5")).string();
  }();
  return path;
}

// Runs one reader entry; its refusal (ArchiveError) is an expected outcome.
template <typename Read>
void section(Read read) {
  try {
    read();
  } catch (const softevo::io::ArchiveError&) {
  }
}

}  // namespace

// libhdf5 runs in this process, unprobed: a crash inside it is a finding of this target (the
// probe would turn it into an error, and fork once per input).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  softevo::io::set_open_probe(false);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scratch_path();
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return 0;
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  section([&] {
    const softevo::io::Archive archive(path);
    section([&] { (void)archive.info(); });
    section([&] { (void)archive.config_text(); });
    std::vector<std::int64_t> generations;
    section([&] { generations = archive.generations(); });
    for (const std::int64_t g : generations) {
      section([&] { (void)archive.generation(g); });
      section([&] { (void)archive.stored_generation_digest(g); });
    }
    section([&] { (void)archive.stats(); });
    section([&] { (void)archive.checkpoint(); });
    (void)softevo::master::check_archive(archive);
  });
  std::remove(path.c_str());
  return 0;
}
