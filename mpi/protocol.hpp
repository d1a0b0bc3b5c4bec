// The message tags of softevo-mpi and who sends what. Rank 0 is the master, ranks 1..N-1 are
// workers; all messages travel on softevo's own duplicate of the caller's communicator
// (mpi/communicator.hpp), so no tag can meet a message of the program that embeds softevo.
//
//   master -> worker  Tag::request  a framed eval request (common/wire.hpp encode_eval_request)
//   worker -> master  Tag::result   a framed eval result (encode_eval_result)
//   master -> worker  Tag::stop     a framed shutdown message carrying the run's exit code
//                                   (encode_shutdown): the worker returns that code. This is
//                                   the only way the exit code reaches a worker.
//   worker -> master  Tag::error    UTF-8 text: the worker refuses a request (config hash
//                                   mismatch); the master ends the run
//   worker -> master  Tag::leaving  UTF-8 text: why the worker stops (a stop signal, its
//                                   launcher died). It has dropped its unit, if any, and
//                                   answers no more requests; it waits for Tag::stop (but not
//                                   for ever). The master stops the run at once, like on
//                                   SIGTERM, and names the rank.
//
// Before any of these, rank 0 broadcasts the start-up status and the canonical config text
// (Communicator::broadcast) and gathers every rank's process (pid and host, for naming a rank
// that died); a failed start-up ends every rank with the same code there.
#pragma once

#include <optional>

namespace softevo::mpi {

// The values 101-104 are those of every softevo-mpi so far (105 is new); they only have to differ
// from each other, but keeping them makes message traces of old and new builds read the same.
enum class Tag : int {
  request = 101,
  result = 102,
  stop = 103,
  error = 104,
  leaving = 105,
};

constexpr const char* tag_name(Tag tag) {
  switch (tag) {
    case Tag::request:
      return "request";
    case Tag::result:
      return "result";
    case Tag::stop:
      return "stop";
    case Tag::error:
      return "error";
    case Tag::leaving:
      return "leaving";
  }
  return "unknown";
}

// The Tag of a raw MPI tag, or nothing if softevo never sends that tag.
constexpr std::optional<Tag> tag_of(int raw) {
  for (Tag t : {Tag::request, Tag::result, Tag::stop, Tag::error, Tag::leaving})
    if (static_cast<int>(t) == raw) return t;
  return std::nullopt;
}

}  // namespace softevo::mpi
