#include "mpi/communicator.hpp"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <ctime>

namespace softevo::mpi {
namespace {

std::string mpi_error_text(int code) {
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  if (MPI_Error_string(code, text, &length) != MPI_SUCCESS)
    return "MPI error " + std::to_string(code);
  return std::string(text, static_cast<std::size_t>(length));
}

std::string tag_label(Tag tag) {
  return std::string(tag_name(tag)) + " (" + std::to_string(static_cast<int>(tag)) + ")";
}

std::string peer_label(int rank) {
  return rank == kAnySource ? "any rank" : "rank " + std::to_string(rank);
}

// `what` says which call, with which peer, tag and size, from the point of view of `rank`.
void check(int code, int rank, const std::string& what) {
  if (code != MPI_SUCCESS)
    throw Error("rank " + std::to_string(rank) + ": " + what + " failed: " + mpi_error_text(code));
}

// MPI counts are ints: a longer message cannot be sent in one call.
int byte_count(std::size_t size, int rank, const std::string& what) {
  if (size > static_cast<std::size_t>(INT_MAX))
    throw Error("rank " + std::to_string(rank) + ": " + what + ": " + std::to_string(size) +
                " bytes exceed the limit of one MPI message (" + std::to_string(INT_MAX) +
                " bytes)");
  return static_cast<int>(size);
}

}  // namespace

void PollBackoff::sleep() {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(pause_);
  ts.tv_nsec = static_cast<long>((pause_ - static_cast<double>(ts.tv_sec)) * 1e9);
  nanosleep(&ts, nullptr);
  pause_ = std::min(pause_ * 1.5, kMaxSeconds);
}

Communicator::Communicator(MPI_Comm parent) {
  int parent_rank = 0;
  MPI_Comm_rank(parent, &parent_rank);
  check(MPI_Comm_dup(parent, &comm_), parent_rank, "MPI_Comm_dup of the caller's communicator");
  check(MPI_Comm_set_errhandler(comm_, MPI_ERRORS_RETURN), parent_rank, "MPI_Comm_set_errhandler");
  check(MPI_Comm_rank(comm_, &rank_), parent_rank, "MPI_Comm_rank");
  check(MPI_Comm_size(comm_, &size_), parent_rank, "MPI_Comm_size");
}

Communicator::~Communicator() {
  // After MPI_Finalize no MPI call is allowed; the communicator is gone with MPI then anyway.
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && comm_ != MPI_COMM_NULL) MPI_Comm_free(&comm_);
}

void Communicator::send(int dest, Tag tag, std::span<const std::uint8_t> bytes) const {
  const std::string what = "MPI_Send of " + std::to_string(bytes.size()) + " bytes with tag " +
                           tag_label(tag) + " to " + peer_label(dest);
  const int count = byte_count(bytes.size(), rank_, what);
  check(MPI_Send(bytes.data(), count, MPI_BYTE, dest, static_cast<int>(tag), comm_), rank_, what);
}

bool Communicator::send_unless(int dest, Tag tag, std::span<const std::uint8_t> bytes,
                               const std::function<bool()>& give_up) const {
  const std::string what = "MPI_Isend of " + std::to_string(bytes.size()) + " bytes with tag " +
                           tag_label(tag) + " to " + peer_label(dest);
  const int count = byte_count(bytes.size(), rank_, what);
  // MPI reads the buffer until the send completes, which for an abandoned send is never known:
  // it is a copy that this communicator keeps for its whole life then.
  std::vector<std::uint8_t> buffer(bytes.begin(), bytes.end());
  MPI_Request request = MPI_REQUEST_NULL;
  check(MPI_Isend(buffer.data(), count, MPI_BYTE, dest, static_cast<int>(tag), comm_, &request),
        rank_, what);
  PollBackoff backoff;
  for (;;) {
    int done = 0;
    check(MPI_Test(&request, &done, MPI_STATUS_IGNORE), rank_, "MPI_Test of an " + what);
    if (done != 0) return true;
    if (give_up()) {
      MPI_Request_free(&request);  // released, not completed
      abandoned_.push_back(std::move(buffer));
      return false;
    }
    backoff.sleep();
  }
}

void Communicator::send(int dest, Tag tag, std::string_view text) const {
  send(dest, tag,
       std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()),
                                     text.size()));
}

std::optional<Envelope> Communicator::poll(int source) const {
  int flag = 0;
  MPI_Status status;
  check(MPI_Iprobe(source, MPI_ANY_TAG, comm_, &flag, &status), rank_,
        "MPI_Iprobe for a message from " + peer_label(source));
  if (flag == 0) return std::nullopt;
  int count = 0;
  check(MPI_Get_count(&status, MPI_BYTE, &count), rank_, "MPI_Get_count");
  const std::optional<Tag> tag = tag_of(status.MPI_TAG);
  if (!tag)
    throw Error("rank " + std::to_string(rank_) + ": a message of " + std::to_string(count) +
                " bytes from rank " + std::to_string(status.MPI_SOURCE) + " has tag " +
                std::to_string(status.MPI_TAG) + ", which softevo never sends");
  return Envelope{status.MPI_SOURCE, *tag, static_cast<std::size_t>(count)};
}

Message Communicator::receive(const Envelope& pending) const {
  Message message{pending.source, pending.tag, std::vector<std::uint8_t>(pending.size)};
  const std::string what = "MPI_Recv of " + std::to_string(pending.size) + " bytes with tag " +
                           tag_label(pending.tag) + " from " + peer_label(pending.source);
  // The probed message is the first one matching source and tag (MPI never lets messages of one
  // sender and tag overtake each other), so it is exactly this receive's message.
  check(MPI_Recv(message.bytes.data(), byte_count(pending.size, rank_, what), MPI_BYTE,
                 pending.source, static_cast<int>(pending.tag), comm_, MPI_STATUS_IGNORE),
        rank_, what);
  return message;
}

Message Communicator::receive(int source) const {
  PollBackoff backoff;
  for (;;) {
    if (const std::optional<Envelope> pending = poll(source)) return receive(*pending);
    backoff.sleep();
  }
}

Message Communicator::receive(int source, Tag expected) const {
  Message message = receive(source);
  if (message.tag != expected)
    throw Error("rank " + std::to_string(rank_) + ": expected a message with tag " +
                tag_label(expected) + " from " + peer_label(source) + ", got tag " +
                tag_label(message.tag) + " (" + std::to_string(message.bytes.size()) +
                " bytes) from rank " + std::to_string(message.source));
  return message;
}

std::string Communicator::broadcast(const std::string& text, int root) const {
  // The length goes first so every rank can size its buffer; every rank then applies the same
  // limit check, so either all ranks throw or none does.
  std::uint64_t size = rank_ == root ? text.size() : 0;
  const std::string from = " from root rank " + std::to_string(root);
  check(MPI_Bcast(&size, 1, MPI_UINT64_T, root, comm_), rank_, "MPI_Bcast of a text length" + from);
  const std::string what = "MPI_Bcast of " + std::to_string(size) + " bytes of text" + from;
  const int count = byte_count(size, rank_, what);
  std::string out = rank_ == root ? text : std::string(size, '\0');
  if (count > 0) check(MPI_Bcast(out.data(), count, MPI_CHAR, root, comm_), rank_, what);
  return out;
}

std::int32_t Communicator::broadcast(std::int32_t value, int root) const {
  check(MPI_Bcast(&value, 1, MPI_INT32_T, root, comm_), rank_,
        "MPI_Bcast of an integer from root rank " + std::to_string(root));
  return value;
}

std::vector<std::string> Communicator::gather(const std::string& text, int root) const {
  const std::string from = " to root rank " + std::to_string(root);
  const int count = byte_count(text.size(), rank_, "MPI_Gatherv of text" + from);
  std::vector<int> counts(rank_ == root ? static_cast<std::size_t>(size_) : 0);
  check(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, root, comm_), rank_,
        "MPI_Gather of text lengths" + from);
  std::vector<int> offsets(counts.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    offsets[r] = byte_count(total, rank_, "MPI_Gatherv of text" + from);
    total += static_cast<std::size_t>(counts[r]);
  }
  std::string all(total, '\0');
  check(MPI_Gatherv(text.data(), count, MPI_CHAR, all.data(), counts.data(), offsets.data(),
                    MPI_CHAR, root, comm_),
        rank_, "MPI_Gatherv of " + std::to_string(text.size()) + " bytes of text" + from);
  std::vector<std::string> texts;
  for (std::size_t r = 0; r < counts.size(); ++r)
    texts.push_back(
        all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(counts[r])));
  return texts;
}

void Communicator::abort(int code) const {
  MPI_Abort(comm_, code);
  std::abort();  // MPI_Abort does not return
}

Environment::Environment(int& argc, char**& argv) {
  // MPI_Init's errors are fatal by the standard's default handler: it returns only on success.
  MPI_Init(&argc, &argv);
}

Environment::~Environment() {
  MPI_Finalize();
}

}  // namespace softevo::mpi
