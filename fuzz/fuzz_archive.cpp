// libFuzzer target: the run-archive reader (io/archive, master/archive_check) on an arbitrary
// file, as `softevo info` and `--resume` read it. Every reader entry runs once, each on its own,
// so that a damaged section does not hide the sections after it: info, config, the generation
// list, every generation and its stored digest, stats and checkpoint; then the integrity checks
// (master/archive_check: config text, rules, the checkpoint's population). A reader may only
// fail with ArchiveError; any other exception, a crash, an allocation beyond the file's size or
// a hang is a finding.
//
// The file goes through the structure probe (io/open_probe.hpp) before libhdf5 opens it here,
// as in every softevo process. Debian 12's libhdf5 1.10.8 has memory errors of its own on
// damaged object headers that no caller can avoid (found by this target in a few seconds:
// a SEGV in H5HG_read under H5Aread of a variable-length string attribute, heap overflows in
// the attribute-message decoding under H5Aexists); the probe is softevo's defence against
// them, so it is part of what is fuzzed. A finding is then a crash in softevo's code, or a
// libhdf5 crash in this process that the probe's walk did not run into first. A crash in the
// probe's child is the expected outcome for such a file (the parent turns it into an error):
// the child reports nothing and leaves no crash artifact (see LLVMFuzzerInitialize).
//
// Speed (each input is a real HDF5 file, opened by libhdf5): every entry runs once, not again
// through fitness_digest and content_digest (they call the same entries on the same bytes and
// only hash what they get), and the input goes to one file in /dev/shm.
#include <fcntl.h>
#include <pthread.h>
#include <sanitizer/common_interface_defs.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

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

// Runs one reader entry; its refusal (ArchiveError) is an expected outcome.
template <typename Read>
void section(Read read) {
  try {
    read();
  } catch (const softevo::io::ArchiveError&) {
  }
}

// In the probe's child (a fork of this process): a sanitizer report there is libhdf5 failing
// on the damaged file, which the parent reports as an error. libFuzzer's death callback would
// save the input as a crash of this target and print its final stats; the child's callback
// only exits, and its report goes to /dev/null instead of the fuzzer's log.
void quiet_probe_child() {
  const int null_fd = ::open("/dev/null", O_WRONLY);
  if (null_fd >= 0) {
    ::dup2(null_fd, STDERR_FILENO);
    ::close(null_fd);
  }
  __sanitizer_set_death_callback([] { ::_exit(1); });
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ::pthread_atfork(nullptr, nullptr, quiet_probe_child);
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
