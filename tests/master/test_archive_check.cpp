// Integrity checks of a run archive (master/archive_check.hpp): every corrupt variant is
// reported by check_archive (what `softevo info` prints) and refused by --resume with a message
// naming the file, the generation and the check; an archive without digests (older builds) is
// still checked by the other rules; `softevo repair`'s rebuilt archive resumes to the digest of
// an uninterrupted run.
#include "master/archive_check.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "io/h5.hpp"
#include "tests/build_tree.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"
#include "tests/sanitizers.hpp"

namespace softevo::master {
namespace {

namespace fs = std::filesystem;

// Edits the archive at `path` in place with the HDF5 layer (the damage a test plants).
void damage(const std::string& path, const std::function<void(const io::h5::File&)>& edit) {
  io::h5::File file = io::h5::File::open(path, io::h5::File::Access::read_write);
  edit(file);
  file.close();
}

void flip_first_double_bit(const io::h5::File& f, const std::string& dataset) {
  const io::h5::Dataset ds = f.open_dataset(dataset);
  std::vector<double> v = ds.read<double>();
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v[0], sizeof bits);
  bits ^= 1ULL << 20;
  std::memcpy(&v[0], &bits, sizeof bits);
  ds.write(v);
}

struct Variant {
  const char* name;
  std::int64_t generation;  // where the problem is reported (-1: archive as a whole)
  const char* check;
  std::function<void(const io::h5::File&)> edit;
};

std::vector<Variant> variants() {
  return {
      {"flipped fitness byte", 1, "digest",
       [](const io::h5::File& f) { flip_first_double_bit(f, "generations/000001/fitness"); }},
      {"flipped status byte", 1, "digest",
       [](const io::h5::File& f) {
         const io::h5::Dataset ds = f.open_dataset("generations/000001/status");
         std::vector<std::uint8_t> v = ds.read<std::uint8_t>();
         v[0] ^= 1;
         ds.write(v);
       }},
      {"unsorted ids", 1, "ids",
       [](const io::h5::File& f) {
         const io::h5::Dataset ds = f.open_dataset("generations/000001/id");
         std::vector<std::int64_t> v = ds.read<std::int64_t>();
         std::swap(v[0], v[1]);
         ds.write(v);
       }},
      {"unreadable generation", 1, "readable",
       [](const io::h5::File& f) { f.open_group("generations/000001").delete_link("fitness"); }},
      {"bad /config", -1, "config",
       [](const io::h5::File& f) {
         const std::string text = f.open_dataset("config").read_string();
         f.delete_link("config");
         f.write_string_dataset("config", text + "# edited\n", io::h5::Charset::utf8);
       }},
      {"generations_done off by one", -1, "generations_done",
       [](const io::h5::File& f) {
         f.write_attribute<std::int64_t>("generations_done",
                                         f.read_attribute<std::int64_t>("generations_done") + 1);
       }},
  };
}

// An interrupted run of 3 of small_config()'s 4 generations, packed into one file (a stop after
// a failed write leaves the segments as they are, so the test packs it as a finished run would):
// resumable when undamaged. The damage tests patch bytes of that one file.
std::string interrupted_run(const test::TmpDir& dir, const std::string& name) {
  const std::string out = dir.file(name);
  const Config config = small_config();
  int generation_updates = 0;
  try {
    run_once(config, out, false, [&](const std::string& step) {
      if (step == "segment: create" && ++generation_updates == 4)  // generation 3
        throw std::runtime_error("stop here");
    });
  } catch (const RunError&) {
  }
  io::finish_archive(out, io::Archive(out).info());
  return out;
}

TEST(ArchiveCheck, AnUndamagedArchivePasses) {
  test::TmpDir dir;
  const std::string out = interrupted_run(dir, "run.h5");
  const ArchiveCheck c = check_archive(io::Archive(out));
  EXPECT_TRUE(c.ok()) << c.describe(out);
  EXPECT_EQ(c.generations_checked, 3);
  EXPECT_EQ(c.generations_with_digest, 3);
  EXPECT_EQ(c.consistent_generations, 3);
}

TEST(ArchiveCheck, EveryCorruptVariantIsReportedAndRefusedByResume) {
  test::TmpDir dir;
  const std::string clean = interrupted_run(dir, "clean.h5");
  for (const Variant& v : variants()) {
    SCOPED_TRACE(v.name);
    const std::string out = dir.file("damaged.h5");
    fs::copy_file(clean, out, fs::copy_options::overwrite_existing);
    damage(out, v.edit);
    const ArchiveCheck c = check_archive(io::Archive(out));
    ASSERT_FALSE(c.ok());
    bool found = false;
    for (const ArchiveProblem& p : c.problems)
      found = found || (p.generation == v.generation && p.check == v.check);
    EXPECT_TRUE(found) << c.describe(out);
    if (v.generation >= 0) {
      EXPECT_EQ(c.consistent_generations, v.generation) << c.describe(out);
    }
    try {
      run_once(small_config(), out, true);
      ADD_FAILURE() << "resumed a damaged archive";
    } catch (const StartupError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(out + ": cannot resume"), std::string::npos) << m;
      EXPECT_NE(m.find(std::string(v.check) + ": "), std::string::npos) << m;
      if (v.generation >= 0) {
        EXPECT_NE(m.find("generation " + std::to_string(v.generation) + ": "), std::string::npos)
            << m;
      }
      EXPECT_NE(m.find("softevo repair " + out), std::string::npos) << m;
    }
  }
}

// Archives written before the digest attribute existed are checked by the other rules: a
// flipped fitness bit still shows in the group's statistics.
TEST(ArchiveCheck, ArchiveWithoutDigestsIsCheckedByTheOtherRules) {
  test::TmpDir dir;
  const std::string out = interrupted_run(dir, "old.h5");
  damage(out, [](const io::h5::File& f) {
    for (const char* g : {"000000", "000001", "000002"})
      ASSERT_GE(H5Adelete(f.open_group(std::string("generations/") + g).id(), "digest"), 0);
  });
  ArchiveCheck c = check_archive(io::Archive(out));
  EXPECT_TRUE(c.ok()) << c.describe(out);
  EXPECT_EQ(c.generations_with_digest, 0);
  damage(out,
         [](const io::h5::File& f) { flip_first_double_bit(f, "generations/000002/fitness"); });
  c = check_archive(io::Archive(out));
  ASSERT_EQ(c.problems.size(), 1u) << c.describe(out);
  EXPECT_EQ(c.problems[0].generation, 2);
  EXPECT_EQ(c.problems[0].check, "statistics");
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

int softevo(const std::string& args) {
  const int rc =
      std::system((test::build_dir() + "/bin/softevo " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// A run of `softevo ARGS...` with its exit code, output, wall time and peak memory.
struct Measured {
  int code = -1;  // -1: killed by a signal
  std::string output;
  double seconds = 0.0;
  long max_rss_kib = 0;
};

Measured softevo_measured(const std::vector<std::string>& args, const std::string& log) {
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
#if !SOFTEVO_TEST_ASAN
    // Before the bounds, one damaged length made info allocate 8.4 GB: fail instead of
    // exhausting the machine (the sanitizer's shadow memory needs an unlimited address space).
    const rlimit as{rlim_t{2} << 30, rlim_t{2} << 30};
    ::setrlimit(RLIMIT_AS, &as);
#endif
    const std::string exe = test::build_dir() + "/bin/softevo";
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  Measured m;
  int status = 0;
  rusage usage{};
  ::wait4(pid, &status, 0, &usage);
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  m.max_rss_kib = usage.ru_maxrss;
  m.output = file_bytes(log);
  return m;
}

// Overwrites `bytes.size()` bytes of the file at `offset` (damage below the HDF5 layer).
void patch(const std::string& path, std::uint64_t offset, const std::string& bytes) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// File offsets of generation 1's first genome: its reference (length u32, collection address,
// object index u32) and the size field of the object in the global heap it points to.
struct GenomeBytes {
  std::uint64_t reference = 0;
  std::uint64_t heap_object_size = 0;
};

GenomeBytes genome_bytes(const std::string& path) {
  const io::h5::File file = io::h5::File::open(path);
  const io::h5::Dataset ds = file.open_dataset("generations/000001/genome");
  GenomeBytes at;
  at.reference = H5Dget_offset(ds.id());
  const std::string bytes = file_bytes(path);
  std::uint64_t collection = 0, object = 0;
  std::memcpy(&collection, bytes.data() + at.reference + 4, 8);
  std::memcpy(&object, bytes.data() + at.reference + 12, 4);
  // Objects follow the 16-byte collection header: index u16, references u16, 4 reserved, size.
  std::uint64_t pos = collection + 16;
  for (;;) {
    std::uint16_t index = 0;
    std::uint64_t size = 0;
    std::memcpy(&index, bytes.data() + pos, 2);
    std::memcpy(&size, bytes.data() + pos + 8, 8);
    if (index == object) break;
    pos += 16 + (size + 7) / 8 * 8;
  }
  at.heap_object_size = pos + 8;
  return at;
}

// Issue 21 item 4: `softevo info` on an archive with one flipped byte took 73 s and 8.4 GB. A
// damaged length, object size or extent is now refused before anything is allocated: info
// ends within seconds, in a few tens of MB, with a message naming the file, the object and
// the limit.
TEST(ArchiveCheck, InfoRefusesDamagedSizesFastAndInBoundedMemory) {
  test::TmpDir dir;
  const std::string clean = interrupted_run(dir, "clean.h5");
  const GenomeBytes at = genome_bytes(clean);
  struct Damage {
    const char* name;
    std::function<void(const std::string&)> apply;
    int code;              // expected exit code of info
    const char* expected;  // in its output
  };
  const std::vector<Damage> cases = {
      {"genome length flipped to 2 GiB",
       [&](const std::string& p) { patch(p, at.reference + 3, "\x7f"); }, 1,
       "/generations/000001/genome: read dataset: row 0 is 2130709"},
      {"heap object size flipped to 1 GiB",
       [&](const std::string& p) { patch(p, at.heap_object_size + 3, "\x40"); }, 2,
       "runs past the end of the collection"},
      {"/stats extent of 2^40 rows",
       [](const std::string& p) {
         damage(p, [](const io::h5::File& f) {
           f.open_dataset("stats").set_extent({hsize_t{1} << 40, io::kStatsColumns});
         });
       },
       1, "/stats is not [G, 6] with G <= 10000000"},
  };
  for (const Damage& d : cases) {
    SCOPED_TRACE(d.name);
    const std::string out = dir.file("damaged.h5");
    fs::copy_file(clean, out, fs::copy_options::overwrite_existing);
    d.apply(out);
    const Measured m = softevo_measured({"info", out}, dir.file("info.log"));
    EXPECT_EQ(m.code, d.code) << m.output;
    EXPECT_NE(m.output.find(d.expected), std::string::npos) << m.output;
    EXPECT_NE(m.output.find(out), std::string::npos) << m.output;
    EXPECT_LT(m.seconds, 20.0);
    EXPECT_LT(m.max_rss_kib, 400 * 1024) << m.output;
  }
}

// `softevo info` exits 1 on a damaged archive; `softevo repair` writes its consistent
// generations to a new file (the damaged one untouched), which --resume completes to the
// digest of an uninterrupted run.
TEST(ArchiveCheck, RepairKeepsTheConsistentGenerationsInANewFile) {
  test::TmpDir dir;
  const std::string ref = dir.file("ref.h5");
  ASSERT_EQ(run_once(small_config(), ref, false), RunOutcome::complete);
  const std::string damaged = interrupted_run(dir, "damaged.h5");
  EXPECT_EQ(softevo("info " + damaged), 0);
  damage(damaged,
         [](const io::h5::File& f) { flip_first_double_bit(f, "generations/000002/fitness"); });
  const std::string before = file_bytes(damaged);
  EXPECT_EQ(softevo("info " + damaged), 1);
  const std::string fixed = dir.file("fixed.h5");
  ASSERT_EQ(softevo("repair " + damaged + " -o " + fixed), 0);
  EXPECT_TRUE(file_bytes(damaged) == before);
  EXPECT_NE(softevo("repair " + damaged + " -o " + fixed), 0);  // never overwrites
  {
    const io::Archive a(fixed);
    EXPECT_EQ(a.info().generations_done, 2);
    EXPECT_EQ(a.info().state, io::RunState::interrupted);
    EXPECT_TRUE(check_archive(a).ok());
  }
  EXPECT_EQ(softevo("info " + fixed), 0);
  ASSERT_EQ(run_once(small_config(), fixed, true), RunOutcome::complete);
  EXPECT_EQ(fitness_digest_of(fixed), fitness_digest_of(ref));
  EXPECT_EQ(hash_hex(io::content_digest(io::Archive(fixed))),
            hash_hex(io::content_digest(io::Archive(ref))));
}

}  // namespace
}  // namespace softevo::master
