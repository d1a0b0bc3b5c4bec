// Body development: CPPN queried on the lattice, thresholds, stiffness binning and the
// post-processing of docs/model.md §6.2-6.6. Output is a BodyPlan in robot-file encoding.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "evo/cppn.hpp"

namespace softevo::evo {

struct DevelopedBody {
  bool valid = false;       // §6.5 step 1: at least one structural cell
  bool actuatable = false;  // §6.5 step 10: at least one chamber
  // Trimmed bounding box; cells: 0 empty, 1..10 material, 11.. chamber in sorted order (§6.6).
  // plan.materials is left EMPTY (the caller fills it from the config); voxel_size default.
  // When !valid the plan is empty (lattice 0 x 0 x 0, no cells).
  BodyPlan plan;
  int chamber_count = 0;
};

// Develops the body of `genome` per §6.2-6.6 with body.lattice, body.distance_input
// ("pneuvox" | "center"), body.presence_threshold, body.pneumatic_threshold, body.max_chambers.
// Throws std::invalid_argument on a bad config (lattice not 3 positive sizes, unknown
// distance_input) or a genome that does not have 4 inputs and 4 outputs.
DevelopedBody develop_body(const CppnGenome& genome, const BodyConfig& body);

// Lattice helpers with scipy.ndimage semantics, exposed for unit tests (§6.5). Grids are
// bool/int vectors of size X*Y*Z in C order (index = (x*Y + y)*Z + z).
namespace morph {
using Dims = std::array<int, 3>;
using Grid = std::vector<std::uint8_t>;  // 0/1
// Background cells 6-connected to the array border stay background; all else becomes true.
Grid fill_holes(const Grid& a, const Dims& d);
// A cell survives iff it and its 26 neighbours are true; outside the array counts as false.
Grid erode26(const Grid& a, const Dims& d);
// a plus all 26-neighbours of a (clipped to the array).
Grid dilate26(const Grid& a, const Dims& d);
// Connected components (6 or 26 connectivity) numbered 1,2,... in order of their first cell in
// C order; 0 = background. Returns the number of components in `count`.
std::vector<int> label(const Grid& a, const Dims& d, int connectivity, int& count);
// numpy.digitize(clip(s,-1,1), linspace(-1,1,10)) in {1..10} (§6.4).
int stiffness_bin(double s);
// numpy.linspace(0, 1, n)[i] (§6.2): i * (1/(n-1)), last value exactly 1.0; n == 1 gives 0.
double linspace01(int i, int n);
// Python 3 round(): round half to even, as an integer (§6.5 step 8).
long round_half_even(double v);
}  // namespace morph

}  // namespace softevo::evo
