// libFuzzer target: the run-archive reader (io/archive, master/archive_check) on an arbitrary
// file: open, info, config, every generation, stats, checkpoint, digests and the integrity
// checks, as `softevo info` runs them. Every input must end in ArchiveError (or a result);
// no crash, no allocation beyond the file's size, no hang.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "io/archive.hpp"
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

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scratch_path();
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return 0;
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  try {
    const softevo::io::Archive archive(path);
    (void)archive.info();
    (void)archive.config_text();
    for (const std::int64_t g : archive.generations()) {
      (void)archive.generation(g);
      (void)archive.stored_generation_digest(g);
    }
    (void)archive.stats();
    (void)archive.checkpoint();
    (void)softevo::master::check_archive(archive);
    (void)softevo::io::fitness_digest(archive);
    (void)softevo::io::content_digest(archive);
  } catch (const softevo::io::ArchiveError&) {
  }
  std::remove(path.c_str());
  return 0;
}
