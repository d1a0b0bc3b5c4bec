// The only code of softevo that calls MPI (tests/common/test_module_rules.cpp checks it).
//
// A Communicator is softevo's private duplicate (MPI_Comm_dup) of the communicator a caller
// hands in, the way Cabana and other MPI libraries do it: messages and collectives of softevo
// then never match those of the caller, even with equal tags. Its error handler is
// MPI_ERRORS_RETURN, so a failing call becomes an mpi::Error naming this rank, the peer, the
// tag and the size instead of killing the job without a word.
//
// Messages are bytes of any length (up to MPI's int count), tagged with an mpi::Tag. Waiting
// never spins a core: Open MPI's blocking receive busy-polls, so receive() probes without
// blocking and sleeps between probes (PollBackoff).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "mpi/protocol.hpp"

namespace softevo::mpi {

inline constexpr int kAnySource = MPI_ANY_SOURCE;

// A failed MPI call or a message that breaks the protocol (unknown or unexpected tag).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A message that has arrived and is not yet received.
struct Envelope {
  int source = 0;
  Tag tag = Tag::request;
  std::size_t size = 0;  // [bytes]
};

struct Message {
  int source = 0;
  Tag tag = Tag::request;
  std::vector<std::uint8_t> bytes;
};

// Sleep between empty polls [s]: starts at kMinSeconds, x1.5 per empty poll, capped at
// kMaxSeconds. 10 ms of added latency is nothing next to a robot evaluation (seconds), and a
// sleeping rank costs ~0% CPU instead of 100%.
class PollBackoff {
 public:
  static constexpr double kMinSeconds = 0.001;
  static constexpr double kMaxSeconds = 0.010;
  void sleep();                           // sleeps, then lengthens the next pause
  void reset() { pause_ = kMinSeconds; }  // after a poll that found a message

 private:
  double pause_ = kMinSeconds;  // [s]
};

class Communicator {
 public:
  // Collective over `parent`: every rank of it must construct one, in the same order.
  explicit Communicator(MPI_Comm parent);
  ~Communicator();
  Communicator(const Communicator&) = delete;
  Communicator& operator=(const Communicator&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  MPI_Comm native() const { return comm_; }  // for tests and interoperation only

  void send(int dest, Tag tag, std::span<const std::uint8_t> bytes) const;
  void send(int dest, Tag tag, std::string_view text) const;
  // As send, but returns false, the message abandoned, once `give_up` returns true while the
  // message has not left (asked between sleeps of PollBackoff). A send to a process that died
  // may never complete (Open MPI's shared-memory transport then waits for ever), so a master
  // that must stop in time sends this way.
  bool send_unless(int dest, Tag tag, std::span<const std::uint8_t> bytes,
                   const std::function<bool()>& give_up) const;

  // The oldest pending message from `source` (or any source), without receiving it; nothing if
  // none has arrived. Throws Error for a message with a tag softevo never sends.
  std::optional<Envelope> poll(int source = kAnySource) const;
  // Receives the message `poll` reported.
  Message receive(const Envelope& pending) const;
  // Waits (sleep-polling) for the next message from `source` and receives it.
  Message receive(int source = kAnySource) const;
  // As above, but the message must carry `expected`: another tag is received and reported as an
  // Error (it would otherwise be misread, or wait forever behind a receive for `expected`).
  Message receive(int source, Tag expected) const;

  // Collective: every rank returns the root's value.
  std::string broadcast(const std::string& text, int root = 0) const;
  std::int32_t broadcast(std::int32_t value, int root = 0) const;
  // Collective: the root returns every rank's `text` by rank; the other ranks return nothing.
  std::vector<std::string> gather(const std::string& text, int root = 0) const;

  // Ends every rank of the job with `code` (MPI_Abort); for errors no rank can recover from.
  [[noreturn]] void abort(int code) const;

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
  mutable std::vector<std::vector<std::uint8_t>> abandoned_;  // buffers of send_unless
  int rank_ = 0;
  int size_ = 1;
};

// MPI_Init on construction and MPI_Finalize on destruction, for a program's main().
class Environment {
 public:
  Environment(int& argc, char**& argv);
  ~Environment();
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;
  MPI_Comm world() const { return MPI_COMM_WORLD; }
};

}  // namespace softevo::mpi
