// The task registry: the one place that maps a TaskKind to its module. A new task adds its
// kind (common/config.hpp), its module and one line here.
#include <stdexcept>

#include "tasks/directed.hpp"
#include "tasks/gait.hpp"
#include "tasks/rotate.hpp"
#include "tasks/task.hpp"

namespace softevo::tasks {

std::unique_ptr<Task> make_task(const Config& config) {
  switch (config.task.kind) {
    case TaskKind::gait:
      return make_gait_task(config);
    case TaskKind::directed:
      return make_directed_task(config);
    case TaskKind::rotate:
      return make_rotate_task(config);
  }
  throw std::invalid_argument(std::string("task.kind ") + to_string(config.task.kind) +
                              " has no task module");
}

TaskKind default_task_for(int controller_task_inputs) {
  const Config defaults;
  for (TaskKind kind : task_kinds()) {
    Config c = defaults;
    c.task.kind = kind;
    if (make_task(c)->controller_inputs() == controller_task_inputs) return kind;
  }
  throw std::invalid_argument("no task feeds " + std::to_string(controller_task_inputs) +
                              " controller inputs");
}

}  // namespace softevo::tasks
