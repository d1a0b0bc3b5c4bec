// The gait task (§7.1). See gait.hpp.
#include "tasks/gait.hpp"

#include "physics/observables.hpp"

namespace softevo::tasks {
namespace {

constexpr double kCmPerM = 100.0;

class GaitScore : public UnitScore {
 public:
  UnitFitness finish(const physics::Model& model, const physics::State& state) override {
    return so_far(model, state);
  }
  UnitFitness so_far(const physics::Model& model, const physics::State& state) const override {
    const Eigen::Vector3d c = physics::centroid_displacement(model, state);
    UnitFitness f;
    f.fitness = gait_fitness(c);
    f.values = {c.x() * kCmPerM};
    return f;
  }
};

class GaitTask : public Task {
 public:
  TaskKind kind() const override { return TaskKind::gait; }
  std::vector<std::string> controller_input_names() const override { return {}; }
  int units() const override { return 1; }
  // mean x displacement (§7.1)
  std::string fitness_unit() const override { return "cm"; }
  std::vector<ComponentName> component_names() const override { return {{"distance", "cm"}}; }
  std::unique_ptr<UnitScore> start_unit(int, const physics::Model&) const override {
    return std::make_unique<GaitScore>();
  }
};

}  // namespace

double gait_fitness(const Eigen::Vector3d& centroid_displacement) {
  return kCmPerM * centroid_displacement.x();
}

std::unique_ptr<Task> make_gait_task(const Config&) {
  return std::make_unique<GaitTask>();
}

}  // namespace softevo::tasks
