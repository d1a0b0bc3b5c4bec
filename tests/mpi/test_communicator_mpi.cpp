// The MPI room (mpi/communicator.hpp), at np = 2 and 3: softevo's communicator is a duplicate of
// the caller's, bytes of any length go through, poll does not receive, broadcast reaches every
// rank, gather collects every rank's text in order, and a message or call that breaks the protocol
// is an Error that says where.
#include "mpi/communicator.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace softevo::mpi {
namespace {

// Bytes that differ per position and per message, so a truncated or shifted copy is noticed.
std::vector<std::uint8_t> pattern(std::size_t size, int salt) {
  std::vector<std::uint8_t> bytes(size);
  for (std::size_t i = 0; i < size; ++i)
    bytes[i] = static_cast<std::uint8_t>((i * 31 + static_cast<std::size_t>(salt) * 7) & 0xFF);
  return bytes;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Communicator, IsACongruentDuplicateOfTheCallersCommunicator) {
  const Communicator comm(MPI_COMM_WORLD);
  int comparison = MPI_UNEQUAL;
  MPI_Comm_compare(comm.native(), MPI_COMM_WORLD, &comparison);
  EXPECT_EQ(comparison, MPI_CONGRUENT) << "same ranks in the same order, but another context";
  int world_rank = -1, world_size = -1;
  MPI_Comm_rank(MPI_COMM_WORLD, &world_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &world_size);
  EXPECT_EQ(comm.rank(), world_rank);
  EXPECT_EQ(comm.size(), world_size);
  MPI_Errhandler handler;
  MPI_Comm_get_errhandler(comm.native(), &handler);
  EXPECT_EQ(handler, MPI_ERRORS_RETURN);
  MPI_Errhandler_free(&handler);
}

TEST(Communicator, MessagesOfTheCallerAndOfSoftevoNeverMeet) {
  const Communicator comm(MPI_COMM_WORLD);
  const int tag = static_cast<int>(Tag::request);  // the same tag on both communicators
  if (comm.rank() == 0) {  // the same rank numbers as in the world (congruent)
    const char caller_text[] = "caller";
    MPI_Send(caller_text, 6, MPI_CHAR, 1, tag, MPI_COMM_WORLD);
    comm.send(1, Tag::request, std::string_view("softevo"));
  } else if (comm.rank() == 1) {
    // Softevo's message is here, yet the caller's probe on the same tag finds only its own.
    const Message ours = comm.receive(0, Tag::request);
    EXPECT_EQ(std::string(ours.bytes.begin(), ours.bytes.end()), "softevo");
    MPI_Status status;
    MPI_Probe(0, tag, MPI_COMM_WORLD, &status);  // the caller's message has arrived
    EXPECT_FALSE(comm.poll().has_value()) << "the caller's message leaked into softevo's";
    char buffer[16] = {};
    MPI_Recv(buffer, 16, MPI_CHAR, 0, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    EXPECT_EQ(std::string(buffer), "caller");
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

TEST(Communicator, SendsAndReceivesEmptyAndLargeMessages) {
  const Communicator comm(MPI_COMM_WORLD);
  const std::vector<std::size_t> sizes = {0, 1, (3u << 20) + 7};  // 0 B, 1 B, 3 MiB + 7 B
  for (std::size_t size : sizes) {
    if (comm.rank() == 0) {
      for (int r = 1; r < comm.size(); ++r) comm.send(r, Tag::request, pattern(size, r));
      for (int r = 1; r < comm.size(); ++r) {
        const Message echo = comm.receive(r, Tag::result);
        EXPECT_EQ(echo.source, r);
        EXPECT_EQ(echo.bytes.size(), size);
        EXPECT_TRUE(echo.bytes == pattern(size, r + 100)) << "echo of " << size << " bytes";
      }
    } else {
      const Message m = comm.receive(0, Tag::request);
      EXPECT_EQ(m.source, 0);
      EXPECT_EQ(m.tag, Tag::request);
      EXPECT_EQ(m.bytes.size(), size);
      EXPECT_TRUE(m.bytes == pattern(size, comm.rank())) << size << " bytes";
      comm.send(0, Tag::result, pattern(size, comm.rank() + 100));
    }
  }
}

TEST(Communicator, PollReportsAPendingMessageWithoutReceivingIt) {
  const Communicator comm(MPI_COMM_WORLD);
  EXPECT_FALSE(comm.poll().has_value()) << "nothing has been sent on a new communicator";
  MPI_Barrier(MPI_COMM_WORLD);
  if (comm.rank() != 0) {
    comm.send(0, Tag::result, pattern(static_cast<std::size_t>(10 * comm.rank()), 1));
    return;
  }
  for (int r = 1; r < comm.size(); ++r) {
    std::optional<Envelope> pending;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    PollBackoff backoff;
    while (!(pending = comm.poll(r)) && std::chrono::steady_clock::now() < deadline)
      backoff.sleep();
    ASSERT_TRUE(pending.has_value()) << "no message from rank " << r << " within 30 s";
    EXPECT_EQ(pending->source, r);
    EXPECT_EQ(pending->tag, Tag::result);
    EXPECT_EQ(pending->size, static_cast<std::size_t>(10 * r));
    const std::optional<Envelope> again = comm.poll(r);  // still pending: poll receives nothing
    ASSERT_TRUE(again.has_value());
    EXPECT_EQ(again->size, pending->size);
    const Message m = comm.receive(*pending);
    EXPECT_TRUE(m.bytes == pattern(static_cast<std::size_t>(10 * r), 1));
    EXPECT_FALSE(comm.poll(r).has_value()) << "received, so no longer pending";
  }
}

TEST(Communicator, BroadcastGivesEveryRankTheRootsValue) {
  const Communicator comm(MPI_COMM_WORLD);
  const std::vector<std::uint8_t> big = pattern((2u << 20) + 3, 5);  // 2 MiB + 3 B
  const std::vector<std::string> texts = {"", "[run]\nseed = 7\n",
                                          std::string(big.begin(), big.end())};
  for (int root : {0, comm.size() - 1}) {
    for (const std::string& text : texts) {
      const std::string got = comm.broadcast(comm.rank() == root ? text : "not the root's", root);
      EXPECT_TRUE(got == text) << "root " << root << ", " << text.size() << " bytes";
    }
    EXPECT_EQ(comm.broadcast(comm.rank() == root ? 1234 + root : -1, root), 1234 + root);
  }
}

TEST(Communicator, GatherGivesTheRootEveryRanksTextInRankOrder) {
  const Communicator comm(MPI_COMM_WORLD);
  for (int root : {0, comm.size() - 1}) {
    // Lengths differ per rank (rank 0's is empty), so a wrong offset shifts every later text.
    const std::string mine = std::string(static_cast<std::size_t>(comm.rank()) * 3, 'x') + "|" +
                             std::to_string(comm.rank() + 10 * root);
    const std::vector<std::string> got = comm.gather(mine, root);
    if (comm.rank() != root) {
      EXPECT_TRUE(got.empty());
      continue;
    }
    ASSERT_EQ(got.size(), static_cast<std::size_t>(comm.size()));
    for (int r = 0; r < comm.size(); ++r)
      EXPECT_EQ(
          got[static_cast<std::size_t>(r)],
          std::string(static_cast<std::size_t>(r) * 3, 'x') + "|" + std::to_string(r + 10 * root));
  }
}

TEST(Communicator, AMessageWithAnotherTagIsAClearError) {
  const Communicator comm(MPI_COMM_WORLD);
  if (comm.rank() == 0) comm.send(1, Tag::result, pattern(5, 0));
  if (comm.rank() == 1) {
    try {
      comm.receive(0, Tag::request);
      ADD_FAILURE() << "a result was accepted where a request was expected";
    } catch (const Error& e) {
      const std::string text = e.what();
      EXPECT_TRUE(contains(text, "rank 1:")) << text;
      EXPECT_TRUE(contains(text, "request (101)")) << text;
      EXPECT_TRUE(contains(text, "result (102)")) << text;
      EXPECT_TRUE(contains(text, "5 bytes")) << text;
      EXPECT_TRUE(contains(text, "from rank 0")) << text;
    }
    EXPECT_FALSE(comm.poll().has_value()) << "the wrong message is consumed, not left behind";
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

TEST(Communicator, AMessageWithATagSoftevoNeverSendsIsAClearError) {
  const Communicator comm(MPI_COMM_WORLD);
  const int foreign_tag = 999;
  if (comm.rank() == 0) {
    const char bytes[3] = {1, 2, 3};
    MPI_Send(bytes, 3, MPI_BYTE, 1, foreign_tag, comm.native());
  }
  if (comm.rank() == 1) {
    try {
      comm.receive(0);
      ADD_FAILURE() << "a message with tag 999 was accepted";
    } catch (const Error& e) {
      const std::string text = e.what();
      EXPECT_TRUE(contains(text, "rank 1:")) << text;
      EXPECT_TRUE(contains(text, "tag 999")) << text;
      EXPECT_TRUE(contains(text, "3 bytes")) << text;
      EXPECT_TRUE(contains(text, "from rank 0")) << text;
    }
    char drain[3];
    MPI_Recv(drain, 3, MPI_BYTE, 0, foreign_tag, comm.native(), MPI_STATUS_IGNORE);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

TEST(Communicator, AFailedCallIsAnErrorNamingRankTagAndSize) {
  const Communicator comm(MPI_COMM_WORLD);
  const int no_such_rank = comm.size() + 5;
  try {
    comm.send(no_such_rank, Tag::stop, pattern(8, 0));
    ADD_FAILURE() << "a send to rank " << no_such_rank << " succeeded";
  } catch (const Error& e) {
    const std::string text = e.what();
    EXPECT_TRUE(contains(text, "rank " + std::to_string(comm.rank()) + ":")) << text;
    EXPECT_TRUE(contains(text, "MPI_Send of 8 bytes")) << text;
    EXPECT_TRUE(contains(text, "stop (103)")) << text;
    EXPECT_TRUE(contains(text, "to rank " + std::to_string(no_such_rank))) << text;
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

}  // namespace
}  // namespace softevo::mpi
