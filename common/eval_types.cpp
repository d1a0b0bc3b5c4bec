#include "common/eval_types.hpp"

namespace softevo {

const char* to_string(EvalStatus status) {
  switch (status) {
    case EvalStatus::ok:
      return "ok";
    case EvalStatus::killed_flipped:
      return "killed: flipped";
    case EvalStatus::killed_exploded:
      return "killed: exploded";
    case EvalStatus::diverged:
      return "diverged";
    case EvalStatus::failed:
      return "failed";
    case EvalStatus::timeout:
      return "timeout";
    case EvalStatus::invalid_body:
      return "invalid body";
  }
  return "unknown";
}

bool is_killed(EvalStatus status) {
  return status != EvalStatus::ok;
}

}  // namespace softevo
