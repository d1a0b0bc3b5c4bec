#include "common/eval_types.hpp"

namespace softevo {

bool is_killed(EvalStatus status) {
  return status != EvalStatus::ok;
}

}  // namespace softevo
