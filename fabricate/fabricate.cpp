// The fabrication grid, its meshes and the inlet channels (fabricate.hpp, docs/fabrication.md).
#include "fabricate/fabricate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <tuple>

#include "render/render.hpp"
#include "scene/cells.hpp"

namespace softevo::fabricate {

namespace {

std::size_t lattice_index(const Eigen::Vector3i& lattice, const Eigen::Vector3i& c) {
  return (static_cast<std::size_t>(c.x()) * lattice.y() + c.y()) * lattice.z() + c.z();
}

bool in_lattice(const Eigen::Vector3i& lattice, const Eigen::Vector3i& c) {
  return (c.array() >= 0).all() && (c.array() < lattice.array()).all();
}

// Union-find over the (quad, corner) incidences of extract_mesh.
struct Classes {
  std::vector<std::uint32_t> parent;
  explicit Classes(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0U); }
  std::uint32_t find(std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

std::string mm_text(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%g mm", metres * 1e3);
  return text;
}

Eigen::Vector3i Grid::cells() const {
  return {static_cast<int>(planes[0].size()) - 1, static_cast<int>(planes[1].size()) - 1,
          static_cast<int>(planes[2].size()) - 1};
}

int Grid::at(int i, int j, int k) const {
  const Eigen::Vector3i n = cells();
  return labels[(static_cast<std::size_t>(i) * n.y() + j) * n.z() + k];
}

int Grid::axis_cell(int axis, double coordinate) const {
  const auto& p = planes[axis];
  if (p.empty() || coordinate < p.front() || coordinate >= p.back()) return -1;
  return static_cast<int>(std::upper_bound(p.begin(), p.end(), coordinate) - p.begin()) - 1;
}

int Grid::label_at(const Eigen::Vector3d& point) const {
  const int i = axis_cell(0, point.x()), j = axis_cell(1, point.y()), k = axis_cell(2, point.z());
  return i < 0 || j < 0 || k < 0 ? -1 : at(i, j, k);
}

double Grid::cell_volume(int i, int j, int k) const {
  return (planes[0][i + 1] - planes[0][i]) * (planes[1][j + 1] - planes[1][j]) *
         (planes[2][k + 1] - planes[2][k]);
}

Grid make_grid(std::array<std::vector<double>, 3> planes,
               const std::function<int(const Eigen::Vector3d& centre)>& label_of) {
  Grid grid;
  for (int a = 0; a < 3; ++a) {
    // Planes computed in different ways for one place (a lattice plane and the end of a box)
    // may differ in the last bits: closer than a nanometre they are one plane, so no cell is
    // a sliver that would give degenerate triangles.
    std::sort(planes[a].begin(), planes[a].end());
    planes[a].erase(std::unique(planes[a].begin(), planes[a].end(),
                                [](double x, double y) { return y - x < 1e-9; }),
                    planes[a].end());
  }
  grid.planes = std::move(planes);
  const Eigen::Vector3i n = grid.cells();
  grid.labels.resize(static_cast<std::size_t>(n.x()) * n.y() * n.z());
  std::size_t index = 0;
  for (int i = 0; i < n.x(); ++i) {
    for (int j = 0; j < n.y(); ++j) {
      for (int k = 0; k < n.z(); ++k) {
        const Eigen::Vector3d centre(0.5 * (grid.planes[0][i] + grid.planes[0][i + 1]),
                                     0.5 * (grid.planes[1][j] + grid.planes[1][j + 1]),
                                     0.5 * (grid.planes[2][k] + grid.planes[2][k + 1]));
        grid.labels[index++] = static_cast<std::int16_t>(label_of(centre));
      }
    }
  }
  return grid;
}

double Mesh::volume() const {
  double v = 0;
  for (const auto& t : triangles) {
    v += vertices[t[0]].dot(vertices[t[1]].cross(vertices[t[2]]));
  }
  return v / 6.0;
}

Mesh extract_mesh(const Grid& grid, const std::function<bool(int label)>& inside,
                  const std::string& name, std::uint64_t max_triangles) {
  const Eigen::Vector3i n = grid.cells();
  std::vector<char> in(grid.labels.size());
  for (std::size_t c = 0; c < in.size(); ++c) in[c] = inside(grid.labels[c]) ? 1 : 0;
  auto inside_at = [&](Eigen::Vector3i c) {
    if ((c.array() < 0).any() || (c.array() >= n.array()).any()) return false;
    return in[(static_cast<std::size_t>(c.x()) * n.y() + c.y()) * n.z() + c.z()] != 0;
  };
  const Eigen::Vector3<std::uint64_t> corners(n.x() + 1, n.y() + 1, n.z() + 1);
  auto corner_id = [&](const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(c.x()) * corners.y() + c.y()) * corners.z() + c.z();
  };
  // One quad per boundary face, counter-clockwise seen from the outside cell.
  struct Quad {
    std::array<std::uint64_t, 4> corner;
    std::uint64_t cell;  // the inside cell it belongs to
  };
  std::vector<Quad> quads;
  auto too_many = [&] {
    throw FabricateError("fabricate: " + name + " would have more than " +
                         std::to_string(max_triangles) + " triangles (the stated limit)");
  };
  std::uint64_t cell_id = 0;
  for (int i = 0; i < n.x(); ++i) {
    for (int j = 0; j < n.y(); ++j) {
      for (int k = 0; k < n.z(); ++k, ++cell_id) {
        const Eigen::Vector3i c(i, j, k);
        if (!inside_at(c)) continue;
        for (int f = 0; f < 6; ++f) {
          const Eigen::Vector3i& step = scene::kFaceSteps[f];
          if (inside_at(c + step)) continue;
          const int a = f / 2, u = (a + 1) % 3, v = (a + 2) % 3;
          Eigen::Vector3i base = c;
          if (f % 2 == 0) base[a] += 1;
          Eigen::Vector3i du = Eigen::Vector3i::Zero(), dv = Eigen::Vector3i::Zero();
          du[u] = 1;
          dv[v] = 1;
          // (u, v, a) is right-handed: u, u+v, v turns counter-clockwise about +a.
          Quad q{{corner_id(base), corner_id(base + du), corner_id(base + du + dv),
                  corner_id(base + dv)},
                 cell_id};
          if (f % 2 == 1) std::swap(q.corner[1], q.corner[3]);
          quads.push_back(q);
          if (2 * quads.size() > max_triangles) too_many();
        }
      }
    }
  }
  // Pair the quads along each edge. An edge has two quads, or four where two inside cells meet
  // only along it; then each quad pairs with the other quad of its own cell, so the two cells
  // stay apart there (a face-connected solid, as a printed part is).
  struct EdgeUse {
    std::uint64_t lo, hi;
    std::uint32_t quad;
    std::uint8_t edge;
  };
  std::vector<EdgeUse> uses;
  uses.reserve(quads.size() * 4);
  for (std::uint32_t q = 0; q < quads.size(); ++q) {
    for (std::uint8_t e = 0; e < 4; ++e) {
      const std::uint64_t a = quads[q].corner[e], b = quads[q].corner[(e + 1) % 4];
      uses.push_back({std::min(a, b), std::max(a, b), q, e});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.lo, x.hi, x.quad, x.edge) < std::tie(y.lo, y.hi, y.quad, y.edge);
  });
  Classes classes(quads.size() * 4);
  std::vector<std::uint32_t> midpoint_of(quads.size() * 4, UINT32_MAX);
  std::uint32_t midpoints = 0;
  auto pair = [&](const EdgeUse& x, const EdgeUse& y) {
    // x runs a -> b, y runs b -> a: x's start is y's end and the other way round.
    classes.join(x.quad * 4 + x.edge, y.quad * 4 + (y.edge + 1) % 4);
    classes.join(x.quad * 4 + (x.edge + 1) % 4, y.quad * 4 + y.edge);
  };
  for (std::size_t s = 0; s < uses.size();) {
    std::size_t e = s;
    while (e < uses.size() && uses[e].lo == uses[s].lo && uses[e].hi == uses[s].hi) ++e;
    if (e - s == 2) {
      pair(uses[s], uses[s + 1]);
    } else if (e - s == 4) {
      for (std::size_t x = s; x < e; ++x) {
        for (std::size_t y = x + 1; y < e; ++y) {
          if (quads[uses[x].quad].cell != quads[uses[y].quad].cell) continue;
          pair(uses[x], uses[y]);
          // The two sheets may still join at both ends (through faces around each end), which
          // would make two edges of the same two vertices: each sheet gets its own vertex at the
          // edge's midpoint, so the edges differ.
          midpoint_of[uses[x].quad * 4 + uses[x].edge] = midpoints;
          midpoint_of[uses[y].quad * 4 + uses[y].edge] = midpoints;
          ++midpoints;
        }
      }
    } else {
      throw std::logic_error("extract_mesh: an edge with " + std::to_string(e - s) + " faces");
    }
    s = e;
  }
  Mesh mesh;
  mesh.name = name;
  std::vector<std::uint32_t> vertex_of(quads.size() * 4, UINT32_MAX);
  auto vertex = [&](std::uint32_t q, int slot) {
    const std::uint32_t root = classes.find(q * 4 + slot);
    if (vertex_of[root] == UINT32_MAX) {
      vertex_of[root] = static_cast<std::uint32_t>(mesh.vertices.size());
      std::uint64_t id = quads[q].corner[slot];
      const int z = static_cast<int>(id % corners.z());
      id /= corners.z();
      const int y = static_cast<int>(id % corners.y());
      const int x = static_cast<int>(id / corners.y());
      mesh.vertices.emplace_back(grid.planes[0][x], grid.planes[1][y], grid.planes[2][z]);
    }
    return vertex_of[root];
  };
  std::vector<std::uint32_t> midpoint_vertex(midpoints, UINT32_MAX);
  auto add_vertex = [&](const Eigen::Vector3d& p) {
    mesh.vertices.push_back(p);
    return static_cast<std::uint32_t>(mesh.vertices.size() - 1);
  };
  mesh.triangles.reserve(quads.size() * 2);
  for (std::uint32_t q = 0; q < quads.size(); ++q) {
    const std::array<std::uint32_t, 4> v{vertex(q, 0), vertex(q, 1), vertex(q, 2), vertex(q, 3)};
    const auto* mid = &midpoint_of[q * 4];
    if (std::all_of(mid, mid + 4, [](std::uint32_t m) { return m == UINT32_MAX; })) {
      mesh.triangles.push_back({v[0], v[1], v[2]});
      mesh.triangles.push_back({v[0], v[2], v[3]});
      continue;
    }
    // A quad with edge midpoints: a fan around its centre (no degenerate triangle).
    std::vector<std::uint32_t> ring;
    for (int e = 0; e < 4; ++e) {
      ring.push_back(v[e]);
      if (mid[e] == UINT32_MAX) continue;
      if (midpoint_vertex[mid[e]] == UINT32_MAX)
        midpoint_vertex[mid[e]] =
            add_vertex(0.5 * (mesh.vertices[v[e]] + mesh.vertices[v[(e + 1) % 4]]));
      ring.push_back(midpoint_vertex[mid[e]]);
    }
    const std::uint32_t centre = add_vertex(0.5 * (mesh.vertices[v[0]] + mesh.vertices[v[2]]));
    for (std::size_t r = 0; r < ring.size(); ++r)
      mesh.triangles.push_back({centre, ring[r], ring[(r + 1) % ring.size()]});
  }
  if (mesh.triangles.size() > max_triangles) too_many();
  return mesh;
}

std::string Fabrication::summary() const {
  char text[256];
  double volume = 0;
  for (const auto& g : groups) volume += g.mesh.volume();
  std::snprintf(text, sizeof text,
                "%zu voxels of %s in %zu material groups, %zu chambers with inlets, %.6g cm^3 "
                "of material",
                voxel_count, mm_text(voxel_size).c_str(), groups.size(), inlets.size(),
                volume * 1e6);
  return text;
}

namespace {

void check_options(const Options& o, double voxel_size) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(o.scale)) throw FabricateError("fabricate: --scale must be a number > 0");
  if (!positive(o.channel_diameter))
    throw FabricateError("fabricate: --channel-diameter must be a number > 0");
  // The wall of a developed chamber is one voxel thick (the shell of docs/model.md §6.5 step 5):
  // a channel as wide as a voxel would leave no wall material beside it.
  if (o.channel_diameter >= voxel_size)
    throw FabricateError("fabricate: --channel-diameter " + mm_text(o.channel_diameter) +
                         " is not narrower than the chamber wall (one voxel, " +
                         mm_text(voxel_size) + "): lower --channel-diameter or raise --scale");
  if (!positive(o.wall)) throw FabricateError("fabricate: --wall must be a number > 0");
  if (!positive(o.dpi_x) || !positive(o.dpi_y))
    throw FabricateError("fabricate: --dpi must be two numbers > 0");
  if (!positive(o.layer)) throw FabricateError("fabricate: --layer-um must be a number > 0");
}

// The shortest straight channel of each chamber (docs/fabrication.md "Channels"): from one of its
// cells along one of the six axes, through wall voxels only (no other chamber, void, or a voxel
// an earlier channel uses), into air from which the ray leaves the lattice without meeting the
// body again (so the mold's pin can run on to the mold wall). Fewest wall voxels wins; ties go to
// the first cell in body order, then the first direction in kFaceSteps order.
std::vector<Inlet> route_inlets(const scene::Body& body, const Eigen::Vector3i& lattice,
                                const std::vector<int>& labels, double s, double d) {
  std::vector<char> used(labels.size(), 0);
  std::vector<Inlet> inlets;
  for (int q = 0; q < body.chamber_count; ++q) {
    int best = -1, best_cell = -1, best_face = -1;
    for (std::size_t j = 0; j < body.chamber_cells.size(); ++j) {
      if (body.chamber_index[j] != q) continue;
      for (int f = 0; f < 6; ++f) {
        const Eigen::Vector3i& step = scene::kFaceSteps[f];
        Eigen::Vector3i c = body.chamber_cells[j] + step;
        int walls = 0;
        bool ok = true;
        while (in_lattice(lattice, c)) {
          const int l = labels[lattice_index(lattice, c)];
          if (!label::is_material(l) || used[lattice_index(lattice, c)]) break;
          ++walls;
          c += step;
        }
        for (; in_lattice(lattice, c); c += step) {
          if (labels[lattice_index(lattice, c)] != label::kOutside) ok = false;
        }
        if (ok && (best < 0 || walls < best)) {
          best = walls;
          best_cell = static_cast<int>(j);
          best_face = f;
        }
      }
    }
    if (best < 0)
      throw FabricateError("fabricate: chamber " + std::to_string(q) +
                           " has no straight path through its wall to the outside (every ray "
                           "from its cells along the six axes meets another chamber, a void, "
                           "another chamber's channel or the body again)");
    Inlet inlet;
    inlet.chamber = q;
    inlet.cell = body.chamber_cells[best_cell];
    inlet.face = best_face;
    inlet.wall_cells = best;
    const Eigen::Vector3i& step = scene::kFaceSteps[best_face];
    for (int w = 1; w <= best; ++w) used[lattice_index(lattice, inlet.cell + w * step)] = 1;
    const int a = best_face / 2;
    Eigen::Vector3d lo = (inlet.cell.cast<double>().array() + 0.5) * s - 0.5 * d;
    Eigen::Vector3d hi = (inlet.cell.cast<double>().array() + 0.5) * s + 0.5 * d;
    if (best_face % 2 == 0) {
      lo[a] = (inlet.cell[a] + 1) * s;
      hi[a] = (inlet.cell[a] + 1 + best) * s;
    } else {
      lo[a] = (inlet.cell[a] - best) * s;
      hi[a] = inlet.cell[a] * s;
    }
    inlet.box = Eigen::AlignedBox3d(lo, hi);
    inlet.mouth = inlet.box.center();
    inlet.mouth[a] = best_face % 2 == 0 ? hi[a] : lo[a];
    inlets.push_back(inlet);
  }
  return inlets;
}

}  // namespace

Fabrication fabricate(const scene::Body& body, const Provenance& provenance,
                      const Options& options) {
  if (body.voxel_cells.empty())
    throw FabricateError("fabricate: the robot has no voxels: nothing to make");
  if (!(body.voxel_size > 0)) throw FabricateError("fabricate: the robot's voxel size is not > 0");
  Fabrication fab;
  fab.options = options;
  fab.provenance = provenance;
  check_options(options, body.voxel_size * options.scale);
  const double s = body.voxel_size * options.scale;
  fab.voxel_size = s;
  const scene::CellIndex cells(body);
  fab.lattice = cells.dims();
  const Eigen::Vector3i& lattice = fab.lattice;
  // A rough bound before any work: at most 6 faces per voxel, each cut into at most 9 pieces by
  // the channel planes of neighbouring chambers, 2 triangles each.
  if (12ULL * body.voxel_cells.size() > options.max_triangles)
    throw FabricateError("fabricate: " + std::to_string(body.voxel_cells.size()) +
                         " voxels would need more than " + std::to_string(options.max_triangles) +
                         " triangles (the stated limit)");

  // Lattice labels: materials and cavities from the body; empty cells are air when 6-connected
  // to the outside of the lattice, else an enclosed void.
  std::vector<int>& labels = fab.lattice_labels;
  labels.assign(static_cast<std::size_t>(lattice.prod()), -1);
  for (std::size_t i = 0; i < body.voxel_cells.size(); ++i)
    labels[lattice_index(lattice, body.voxel_cells[i])] = body.voxel_material[i];
  for (std::size_t j = 0; j < body.chamber_cells.size(); ++j)
    labels[lattice_index(lattice, body.chamber_cells[j])] = label::kCavity + body.chamber_index[j];
  std::vector<Eigen::Vector3i> stack;
  for (int x = 0; x < lattice.x(); ++x) {
    for (int y = 0; y < lattice.y(); ++y) {
      for (int z = 0; z < lattice.z(); ++z) {
        const Eigen::Vector3i c(x, y, z);
        const bool border = x == 0 || y == 0 || z == 0 || x == lattice.x() - 1 ||
                            y == lattice.y() - 1 || z == lattice.z() - 1;
        if (border && labels[lattice_index(lattice, c)] == -1) {
          labels[lattice_index(lattice, c)] = label::kOutside;
          stack.push_back(c);
        }
      }
    }
  }
  while (!stack.empty()) {
    const Eigen::Vector3i c = stack.back();
    stack.pop_back();
    for (const auto& step : scene::kFaceSteps) {
      const Eigen::Vector3i m = c + step;
      if (in_lattice(lattice, m) && labels[lattice_index(lattice, m)] == -1) {
        labels[lattice_index(lattice, m)] = label::kOutside;
        stack.push_back(m);
      }
    }
  }
  for (int& l : labels) {
    if (l == -1) {
      l = label::kVoid;
      ++fab.void_cells;
    }
  }
  fab.voxel_count = body.voxel_cells.size();
  fab.cavity_cells = body.chamber_cells.size();

  fab.inlets = route_inlets(body, lattice, labels, s, options.channel_diameter);
  std::array<std::vector<double>, 3> planes;
  for (int a = 0; a < 3; ++a) {
    for (int i = 0; i <= lattice[a]; ++i) planes[a].push_back(i * s);
  }
  for (const Inlet& inlet : fab.inlets) {
    for (int a = 0; a < 3; ++a) {
      if (a == inlet.face / 2) continue;
      planes[a].push_back(inlet.box.min()[a]);
      planes[a].push_back(inlet.box.max()[a]);
    }
    fab.channel_volume += inlet.box.volume();
  }
  fab.grid = make_grid(planes, [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3i c(static_cast<int>(std::floor(p.x() / s)),
                            static_cast<int>(std::floor(p.y() / s)),
                            static_cast<int>(std::floor(p.z() / s)));
    for (const Inlet& inlet : fab.inlets) {
      if (inlet.box.contains(p)) return label::kChannel + inlet.chamber;
    }
    return labels[lattice_index(lattice, c)];
  });

  if (!options.meshes) return fab;
  std::vector<std::size_t> count(11, 0);
  for (int m : body.voxel_material) ++count[static_cast<std::size_t>(std::clamp(m, 0, 10))];
  std::uint64_t triangles_left = options.max_triangles;
  for (int m = 1; m <= 10; ++m) {
    if (count[m] == 0) continue;
    MaterialGroup g;
    g.material = m;
    g.youngs_modulus = static_cast<std::size_t>(m) <= provenance.youngs_modulus.size()
                           ? provenance.youngs_modulus[m - 1]
                           : 1.0e4 * m;  // the robot file's default (docs/model.md §10)
    g.colour = render::material_colour(m, body.material_count);
    g.voxels = count[m];
    char name[64];
    std::snprintf(name, sizeof name, "E%.0fPa", g.youngs_modulus);
    g.name = name;
    if (std::any_of(fab.groups.begin(), fab.groups.end(), [&](const MaterialGroup& other) {
          return other.youngs_modulus == g.youngs_modulus;
        }))
      g.name += "-m" + std::to_string(m);
    g.mesh = extract_mesh(
        fab.grid, [m](int l) { return l == m; }, g.name, triangles_left);
    triangles_left -= g.mesh.triangles.size();
    fab.groups.push_back(std::move(g));
  }
  return fab;
}

std::vector<ChannelPiece> channel_pieces(const Fabrication& fab, const scene::Body& body) {
  const scene::CellIndex cells(body);
  const double s = fab.voxel_size;
  std::vector<ChannelPiece> pieces;
  for (const Inlet& in : fab.inlets) {
    for (int w = 1; w <= in.wall_cells; ++w) {
      const Eigen::Vector3i c = in.cell + w * scene::kFaceSteps[in.face];
      const Eigen::Vector3d lo = c.cast<double>() * s, hi = lo + Eigen::Vector3d::Constant(s);
      const Eigen::AlignedBox3d part = in.box.intersection(Eigen::AlignedBox3d(lo, hi));
      // The voxel's centre is at s * (i, j, k) in the simulation (docs/model.md §2.1), its
      // cube around it; here the cube is [lo, hi].
      pieces.push_back({in.chamber, cells.at(c), part.center() - (lo + hi) / 2, part.sizes()});
    }
  }
  return pieces;
}

Cutaway cut_away(const scene::Body& body, const std::vector<scene::Pose>& poses,
                 std::optional<int> cut_y) {
  const scene::CellIndex cells(body);
  const int rows = cells.dims().y();
  // The channels of the whole body (they are routed on it); a body fabricate refuses (a chamber
  // with no way out) is cut all the same, without channels.
  std::vector<ChannelPiece> pieces;
  try {
    Options inlets_only;
    inlets_only.meshes = false;
    pieces = channel_pieces(fabricate(body, {}, inlets_only), body);
  } catch (const FabricateError&) {
  }
  Cutaway cut;
  if (cut_y) {
    if (*cut_y < 0 || *cut_y >= rows)
      throw FabricateError("render: --cutaway y=" + std::to_string(*cut_y) +
                           " is outside the lattice (rows 0 to " + std::to_string(rows - 1) + ")");
    cut.cut_y = *cut_y;
  } else {
    // Every channel kept whole (rows up to the first row a channel passes), and among those
    // rows the one cutting through the most chamber cells (the deepest on ties).
    int last = rows - 1;
    for (const ChannelPiece& p : pieces) last = std::min(last, body.voxel_cells[p.voxel].y());
    std::vector<int> per_row(static_cast<std::size_t>(rows), 0);
    for (const auto& c : body.chamber_cells) ++per_row[static_cast<std::size_t>(c.y())];
    for (int y = 0; y <= last; ++y) {
      if (per_row[y] >= per_row[cut.cut_y]) cut.cut_y = y;
    }
  }
  cut.body = body;
  cut.body.voxel_cells.clear();
  cut.body.voxel_material.clear();
  cut.body.chamber_cells.clear();
  cut.body.chamber_index.clear();
  std::vector<int> new_index(body.voxel_cells.size(), -1);
  for (std::size_t i = 0; i < body.voxel_cells.size(); ++i) {
    if (body.voxel_cells[i].y() < cut.cut_y) continue;
    new_index[i] = static_cast<int>(cut.body.voxel_cells.size());
    cut.body.voxel_cells.push_back(body.voxel_cells[i]);
    cut.body.voxel_material.push_back(body.voxel_material[i]);
  }
  if (cut.body.voxel_cells.empty())
    throw FabricateError("render: --cutaway y=" + std::to_string(cut.cut_y) + " leaves no voxel");
  for (std::size_t j = 0; j < body.chamber_cells.size(); ++j) {
    if (body.chamber_cells[j].y() < cut.cut_y) continue;
    cut.body.chamber_cells.push_back(body.chamber_cells[j]);
    cut.body.chamber_index.push_back(body.chamber_index[j]);
  }
  for (const scene::Pose& pose : poses) {
    scene::Pose kept = pose;
    kept.position.clear();
    kept.orientation.clear();
    for (std::size_t i = 0; i < body.voxel_cells.size(); ++i) {
      if (new_index[i] < 0) continue;
      kept.position.push_back(pose.position[i]);
      kept.orientation.push_back(pose.orientation[i]);
    }
    cut.poses.push_back(std::move(kept));
  }
  for (ChannelPiece p : pieces) {
    if (new_index[static_cast<std::size_t>(p.voxel)] < 0) continue;
    p.voxel = new_index[static_cast<std::size_t>(p.voxel)];
    cut.channels.push_back(p);
  }
  return cut;
}

}  // namespace softevo::fabricate
