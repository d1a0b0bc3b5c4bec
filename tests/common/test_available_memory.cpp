// What this process may still allocate (common/available_memory.hpp): the machine's, and less
// under an address-space limit.
#include "common/available_memory.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <optional>

#include "tests/sanitizers.hpp"

namespace softevo {
namespace {

TEST(AvailableMemory, IsKnownOnLinux) {
  const std::optional<AvailableMemory> here = available_memory();
  ASSERT_TRUE(here.has_value());
  EXPECT_GT(here->bytes, 0u);
  EXPECT_FALSE(here->where.empty());
  EXPECT_EQ(mebibytes(std::uint64_t{3} << 20), "3 MiB");
}

// Under `ulimit -v` an allocation beyond the limit fails whatever the machine has (issue 29: a
// huge render ended in std::bad_alloc); the limit less the mapped address space is what is left.
TEST(AvailableMemory, AddressSpaceLimitCounts) {
  if (SOFTEVO_TEST_ASAN)
    GTEST_SKIP() << "an AddressSanitizer process maps terabytes of shadow memory: no RLIMIT_AS "
                    "can be set below what it has mapped";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::optional<AvailableMemory> before = available_memory();
    if (!before) ::_exit(1);
    struct rlimit limit {};
    limit.rlim_cur = limit.rlim_max = std::uint64_t{4} << 30;  // above what a test maps
    if (::setrlimit(RLIMIT_AS, &limit) != 0) ::_exit(2);
    const std::optional<AvailableMemory> after = available_memory();
    if (!after || after->bytes >= limit.rlim_cur) ::_exit(3);
    // The machine's own may be smaller still; otherwise the limit is named.
    if (after->bytes < before->bytes && after->where.find("ulimit -v") == std::string::npos)
      ::_exit(4);
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace softevo
