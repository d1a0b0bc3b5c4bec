#include "master/unit_cost.hpp"

#include <algorithm>

#include "common/body_plan.hpp"
#include "evo/development.hpp"

namespace softevo::master {

double predicted_unit_cost(const evo::Genome& genome, const BodyConfig& body) {
  const evo::DevelopedBody developed = evo::develop_body(genome.cppn, body);
  if (!developed.valid || !developed.actuatable) return 0.0;
  return static_cast<double>(std::count_if(developed.plan.cells.begin(), developed.plan.cells.end(),
                                           [](int cell) { return cell != 0; }));
}

}  // namespace softevo::master
