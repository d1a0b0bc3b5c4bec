#include "master/run_state.hpp"

namespace softevo::master {

std::string resume_note(std::int64_t generations_done) {
  const std::string next = std::to_string(generations_done);
  if (generations_done <= 0)
    return "the archive holds no generation yet and --resume starts at generation 0";
  return "the archive keeps generations 0-" + std::to_string(generations_done - 1) +
         " and --resume continues from generation " + next;
}

std::optional<std::string> previous_run_note(const io::RunInfo& info,
                                             const std::optional<std::string>& lock_holder,
                                             std::optional<std::int64_t> generations) {
  const std::string done = std::to_string(info.generations_done);
  const std::string at =
      generations && info.generations_done >= *generations
          ? "after archiving its last generation (" + std::to_string(info.generations_done - 1) +
                "); --resume marks it complete"
          : "at generation " + done + "; --resume continues from generation " + done;
  if (info.state == io::RunState::interrupted)
    return "the previous run on this archive was interrupted (it stopped after a signal or an "
           "error, see its log) " +
           at;
  if (info.state == io::RunState::running && !lock_holder)
    return "the previous run on this archive was interrupted (its process died without "
           "closing: killed rank, node failure, ...) " +
           at;
  return std::nullopt;
}

}  // namespace softevo::master
