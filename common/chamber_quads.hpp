// Chamber wall meshes derived from a body plan's cells (docs/model.md §6.7, `make_pneu_quads`).
// Plain lattice logic: lives in common/ because physics (pneumatics) needs it and must not
// depend on evo/.
#pragma once

#include <array>
#include <vector>

#include "common/body_plan.hpp"

namespace softevo {

// One quad = 4 lattice coordinates (x, y, z) of structural wall cells. Split into triangles
// (a,b,c) and (c,d,a); every triangle normal (c-b)x(a-b) points into the cavity (§3.1).
struct ChamberQuads {
  std::vector<std::array<std::array<int, 3>, 4>> quads;
};

// One entry per chamber q = 0..plan.chamber_count()-1 (cell value 11+q), quads exactly as §6.7:
// wall W = dilate26(Pc) minus Pc; six passes (XY +z, XY -z, XZ -y, XZ +y, YZ +x, YZ -x), each
// iterating x, y, z; a quad is emitted at wall cell (x,y,z) iff its other three corners are wall
// cells inside the lattice and at least one of the 4 corners shifted by the pass normal is in
// Pc. Throws std::invalid_argument if cells.size() does not match the lattice.
std::vector<ChamberQuads> chamber_quads(const BodyPlan& plan);

}  // namespace softevo
