#include "common/chamber_quads.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace softevo {

namespace {

struct Pass {
  std::array<int, 3> step;  // in-plane step (dx, dy, dz); 0 on the normal axis
  int normal_axis;          // 0 = x, 1 = y, 2 = z
  int normal;               // +1 / -1: side of the plane the cavity is probed on
  std::array<int, 2> axes;  // the two in-plane axes, first = the one stepped by corner 1
};

// §6.7 table, in pass order. Corners from (x,y,z): c0 = p, c1 = p + step along axes[0],
// c2 = p + step along both axes, c3 = p + step along axes[1].
constexpr std::array<Pass, 6> kPasses{{
    {{1, 1, 0}, 2, +1, {0, 1}},   // 1: XY, normal +z
    {{1, -1, 0}, 2, -1, {0, 1}},  // 2: XY, normal -z
    {{1, 0, 1}, 1, -1, {0, 2}},   // 3: XZ, normal -y
    {{1, 0, -1}, 1, +1, {0, 2}},  // 4: XZ, normal +y
    {{0, 1, 1}, 0, +1, {1, 2}},   // 5: YZ, normal +x
    {{0, 1, -1}, 0, -1, {1, 2}},  // 6: YZ, normal -x
}};

}  // namespace

std::vector<ChamberQuads> chamber_quads(const BodyPlan& plan) {
  const auto& dims = plan.lattice;
  if (dims[0] < 0 || dims[1] < 0 || dims[2] < 0 ||
      plan.cells.size() != static_cast<std::size_t>(dims[0]) * static_cast<std::size_t>(dims[1]) *
                               static_cast<std::size_t>(dims[2])) {
    throw std::invalid_argument("chamber_quads: cells has " + std::to_string(plan.cells.size()) +
                                " entries, lattice " + std::to_string(dims[0]) + "x" +
                                std::to_string(dims[1]) + "x" + std::to_string(dims[2]));
  }
  const int chambers = plan.chamber_count();
  std::vector<ChamberQuads> result(static_cast<std::size_t>(chambers));
  const std::size_t n = plan.cells.size();
  std::vector<std::uint8_t> cavity(n), wall(n);

  auto inside = [&](const std::array<int, 3>& p) {
    return p[0] >= 0 && p[1] >= 0 && p[2] >= 0 && p[0] < dims[0] && p[1] < dims[1] &&
           p[2] < dims[2];
  };
  auto index = [&](const std::array<int, 3>& p) { return plan.cell_index(p[0], p[1], p[2]); };

  for (int q = 0; q < chambers; ++q) {
    const int id = kFirstChamberCell + q;
    // Pc = (V == id); W = dilate26(Pc) and not Pc (§6.7).
    for (std::size_t i = 0; i < n; ++i) cavity[i] = plan.cells[i] == id ? 1 : 0;
    std::fill(wall.begin(), wall.end(), std::uint8_t{0});
    for (int x = 0; x < dims[0]; ++x)
      for (int y = 0; y < dims[1]; ++y)
        for (int z = 0; z < dims[2]; ++z) {
          if (!cavity[plan.cell_index(x, y, z)]) continue;
          for (int ax = -1; ax <= 1; ++ax)
            for (int ay = -1; ay <= 1; ++ay)
              for (int az = -1; az <= 1; ++az) {
                const std::array<int, 3> p{x + ax, y + ay, z + az};
                if (inside(p) && !cavity[index(p)]) wall[index(p)] = 1;
              }
        }

    auto& quads = result[static_cast<std::size_t>(q)].quads;
    for (const Pass& pass : kPasses) {
      for (int x = 0; x < dims[0]; ++x)
        for (int y = 0; y < dims[1]; ++y)
          for (int z = 0; z < dims[2]; ++z) {
            const std::array<int, 3> c0{x, y, z};
            if (!wall[index(c0)]) continue;
            std::array<int, 3> c1 = c0, c3 = c0;
            c1[pass.axes[0]] += pass.step[pass.axes[0]];
            c3[pass.axes[1]] += pass.step[pass.axes[1]];
            std::array<int, 3> c2 = c1;
            c2[pass.axes[1]] += pass.step[pass.axes[1]];
            const std::array<std::array<int, 3>, 4> quad{c0, c1, c2, c3};
            bool corners_ok = true;
            for (int k = 1; k < 4 && corners_ok; ++k)
              corners_ok = inside(quad[k]) && wall[index(quad[k])];
            if (!corners_ok) continue;
            // Probe: the cavity must lie on the normal side of the quad (orientation rule).
            bool touches_cavity = false;
            for (const auto& corner : quad) {
              std::array<int, 3> probe = corner;
              probe[pass.normal_axis] += pass.normal;
              if (inside(probe) && cavity[index(probe)]) touches_cavity = true;
            }
            if (touches_cavity) quads.push_back(quad);
          }
    }
  }
  return result;
}

}  // namespace softevo
