// The structure probe before libhdf5 opens a file (io/h5_probe.cpp, io/open_probe.hpp): a file
// whose damage crashes libhdf5 is refused with an error naming it, the process survives and the
// file is left as it was; good files open as before.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "io/h5.hpp"
#include "io/open_probe.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/sanitizers.hpp"

namespace softevo::io::h5 {
namespace {

using test::TmpDir;

std::vector<char> bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A file in HDF5's default (old-style, unchecksummed) formats, as softevo writes them, whose
// root carries the variable-length string attribute `format` = "abcd". Its value is stored as a
// reference (length u32, global heap collection address, object index u32) in the root's
// object header; `damage` changes the reference's bytes (at the first byte of the length).
template <typename Damage>
std::string file_with_damaged_reference(const TmpDir& d, const std::string& name, Damage damage) {
  const std::string path = d.file(name);
  {
    const File file = File::create(path);
    file.write_string_attribute("format", "abcd", Charset::utf8);
  }
  std::vector<char> bytes = bytes_of(path);
  const std::string view(bytes.begin(), bytes.end());
  const std::size_t collection = view.find("GCOL");
  EXPECT_NE(collection, std::string::npos) << "no global heap collection in " << path;
  std::string reference("\x04\0\0\0", 4);
  for (int i = 0; i < 8; ++i)
    reference += static_cast<char>((static_cast<std::uint64_t>(collection) >> (8 * i)) & 0xff);
  const std::size_t at = view.find(reference);
  EXPECT_NE(at, std::string::npos) << "the attribute's heap reference is not in " << path;
  if (at == std::string::npos) return path;
  damage(bytes, at);
  write_bytes(path, bytes);
  return path;
}

// The damage: one byte of the object index, so that the index names an object the collection
// does not have. libhdf5 1.10 reads such an index without checking it and crashes (SIGSEGV in
// H5HG_read; found by fuzzing, one flipped byte of a seed archive).
std::string damaged_file(const TmpDir& d) {
  return file_with_damaged_reference(d, "damaged.h5", [](std::vector<char>& bytes, std::size_t at) {
    bytes[at + 4 + 8 + 3] = 0x3d;  // object index 2 -> 2 + 61 * 2^24
  });
}

void read_format(const std::string& path) {
  (void)File::open(path).read_string_attribute("format");
}

// The damage must crash libhdf5 itself; otherwise this file no longer tests the probe.
bool died(int status) {
  // A signal, or the sanitizers' report of one (they exit non-zero instead).
  return WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) != 0);
}

TEST(H5ProbeDeathTest, TheDamagedFileCrashesLibhdf5WhenUnprobed) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  TmpDir d;
  const std::string path = damaged_file(d);
  EXPECT_EXIT(
      {
        set_open_probe(false);
        read_format(path);
        std::_Exit(0);
      },
      died, "");
}

TEST(H5Probe, ADamagedFileThatCrashesLibhdf5IsAnErrorAndStaysUnchanged) {
  ASSERT_TRUE(open_probe_enabled());
  TmpDir d;
  const std::string path = damaged_file(d);
  const std::vector<char> before = bytes_of(path);
  struct stat st_before {};
  ASSERT_EQ(::stat(path.c_str(), &st_before), 0);
  try {
    read_format(path);
    FAIL() << "the damaged file was opened";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(message.find("damaged HDF5 file"), std::string::npos) << message;
    EXPECT_NE(message.find("the file was not changed"), std::string::npos) << message;
  }
  struct stat st_after {};
  ASSERT_EQ(::stat(path.c_str(), &st_after), 0);
  EXPECT_EQ(bytes_of(path), before);
  EXPECT_EQ(st_after.st_mtim.tv_sec, st_before.st_mtim.tv_sec);
  EXPECT_EQ(st_after.st_mtim.tv_nsec, st_before.st_mtim.tv_nsec);
  // Refused again on the next open: a failed probe is not remembered as passed.
  EXPECT_THROW(read_format(path), Error);
}

// The damage: the sequence length, 4 -> 0x30000000 (768 MiB). libhdf5 sizes its conversion
// buffers by that length before it finds that the heap object is 4 bytes long: it allocated and
// filled 1.9 GB for a 25 kB archive damaged this way (found by fuzzing). The probe's child
// makes that allocation and the file is refused, so this process never makes it.
TEST(H5Probe, AFileThatMakesLibhdf5AllocateGigabytesIsRefused) {
  TmpDir d;
  const std::string path =
      file_with_damaged_reference(d, "long.h5", [](std::vector<char>& bytes, std::size_t at) {
        bytes[at + 3] = 0x30;
        bytes[at] = 0;
      });
  struct rusage usage {};
  ASSERT_EQ(::getrusage(RUSAGE_SELF, &usage), 0);
  const long peak_before_kb = usage.ru_maxrss;
  try {
    read_format(path);
    FAIL() << "the damaged file was opened";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("damaged HDF5 file"), std::string::npos) << message;
#if SOFTEVO_TEST_ASAN
    // AddressSanitizer's allocator ends the child when an allocation fails (unless
    // allocator_may_return_null=1) instead of returning null to libhdf5: still refused.
    EXPECT_TRUE(message.find("MB of memory") != std::string::npos ||
                message.find("failed (exit status") != std::string::npos)
        << message;
#else
    EXPECT_NE(message.find("MB of memory"), std::string::npos) << message;
#endif
    EXPECT_NE(message.find("the file was not changed"), std::string::npos) << message;
  }
  ASSERT_EQ(::getrusage(RUSAGE_SELF, &usage), 0);
  EXPECT_LT(usage.ru_maxrss - peak_before_kb, 128 * 1024) << "kB more at peak in this process";
}

TEST(H5Probe, GoodFilesOpenAndReadAsBefore) {
  TmpDir d;
  const std::string path = d.file("good.h5");
  {
    const File file = File::create(path);
    file.write_string_attribute("format", "abcd", Charset::utf8);
    const Group g = file.create_group("g");
    g.write_dataset<double>("x", {2}, {1.5, 2.5});
    g.write_byte_rows("rows", {{1, 2}, {3}});
    file.create_external_link("elsewhere", {"missing.h5", "/"});
  }
  for (int i = 0; i < 2; ++i) {  // the second open of the same version is not probed again
    const File file = File::open(path);
    EXPECT_EQ(file.read_string_attribute("format"), "abcd");
    EXPECT_EQ(file.open_group("g").read_dataset<double>("x"), (std::vector<double>{1.5, 2.5}));
  }
}

}  // namespace
}  // namespace softevo::io::h5
