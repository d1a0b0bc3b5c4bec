#include "physics/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <utility>

namespace softevo::physics {

namespace {

// Material constants of one structural voxel material (§2.1, Voxelyze VX_MaterialVoxel), float.
struct VoxelMaterial {
  float e;    // Young's modulus [Pa]
  float rho;  // density [kg/m^3]
  VoxelConst c;
};

VoxelMaterial make_voxel_material(const StructuralMaterial& mat, double s,
                                  const PhysicsConfig& cfg) {
  VoxelMaterial vm{};
  vm.e = static_cast<float>(mat.youngs_modulus);
  vm.rho = static_cast<float>(mat.density);
  VoxelConst& c = vm.c;
  // §2.1: m = rho s^3 (double volume, float mass); I = m s^2 / 6 ("1D approx"), float.
  const double volume = s * s * s;
  c.mass = static_cast<float>(volume * vm.rho);
  const float inertia = static_cast<float>(c.mass * s * s / 6.0f);
  c.inv_mass = 1.0f / c.mass;
  c.inv_inertia = 1.0f / inertia;
  const float sqrt_mass = std::sqrt(c.mass);
  // 2 sqrt(m E s) and 2 sqrt(I E s^3): translational / rotational damping bases (float).
  const float two_sq_mes = static_cast<float>(2.0f * std::sqrt(c.mass * vm.e * s));
  const float two_sq_ies3 = static_cast<float>(2.0f * std::sqrt(inertia * vm.e * s * s * s));
  const float zeta_int = static_cast<float>(cfg.internal_damping);
  const float zeta_glob = static_cast<float>(cfg.global_damping);
  const float zeta_col = static_cast<float>(cfg.collision_damping);
  c.c_glob = zeta_glob * two_sq_mes;
  c.c_glob_rot = zeta_glob * two_sq_ies3;
  c.c_col = zeta_col * two_sq_mes;
  // k_pen = 2 E s ("EA/L with L = s/2"), float.
  c.k_pen = static_cast<float>(2 * vm.e * s);
  // gravity force = -m * g * gravMult (float; g enters as a float like the 9.80665f literal)
  c.gravity_force = -c.mass * static_cast<float>(cfg.gravity) * 1.0f;
  // §2.5 damping multiplier numerator 2 sqrt(m) zeta_int (divided by previousDt at use)
  c.damp_base = 2 * sqrt_mass * zeta_int;
  c.mu_static = static_cast<float>(cfg.static_friction);
  c.mu_kinetic = static_cast<float>(cfg.kinetic_friction);
  return vm;
}

// §2.1 link material of voxel materials (m1, m2) in the order of first creation: E_L =
// 2 E1 E2 / (E1 + E2) (springs in series, float), beam constants with L = (float)s.
LinkConst make_link_const(float e1, float e2, double s) {
  LinkConst k{};
  const float e = 2.0f * e1 * e2 / (e1 + e2);
  const float l = static_cast<float>(s);
  const float nu = 0.0f;
  k.e_area = e;
  k.a2 = e * l * l * l / (12.0f * (1 + nu));  // torsion GJ/L [N m]
  const float a1 = e * l;                     // axial EA/L [N/m]
  k.b1 = e * l;                               // 12EI/L^3 [N/m]
  k.b2 = e * l * l / 2.0f;                    // 6EI/L^2 [N]
  k.b3 = e * l * l * l / 6.0f;                // 2EI/L [N m]
  k.sq_a1 = std::sqrt(a1);
  k.sq_a2xip = std::sqrt(k.a2 * l * l / 6.0f);
  k.sq_b1 = std::sqrt(k.b1);
  k.sq_b2xfmp = std::sqrt(k.b2 * l / 2.0f);
  k.sq_b3xip = std::sqrt(k.b3 * l * l / 6.0f);
  // transverse area: mean of the two voxels' (float)s * (float)s (nu = 0)
  k.area = 0.5f * (l * l + l * l);
  return k;
}

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("physics::build_model: " + what);
}

}  // namespace

float recommended_time_step(const Model& model) {
  // §2.14: omega^2_max = max over links of a1 / min(m_N, m_P) (float); without links, max over
  // voxels of E s / m; dt = 1 / (6.283185 sqrt(omega^2_max)).
  float max_freq2 = 0.0f;
  const float l = static_cast<float>(model.voxel_size);
  for (int i = 0; i < model.link_count; ++i) {
    const float a1 = model.link_const[i].e_area * l;
    const float m = std::min(model.voxel_const[model.link_neg[i]].mass,
                             model.voxel_const[model.link_pos[i]].mass);
    max_freq2 = std::max(max_freq2, a1 / m);
  }
  if (max_freq2 <= 0.0f) {
    for (int v = 0; v < model.voxel_count; ++v) {
      // E is recovered from k_pen = 2 E s: E s = k_pen / 2 (exact halving in float)
      const float es = model.voxel_const[v].k_pen / 2.0f;
      max_freq2 = std::max(max_freq2, es / model.voxel_const[v].mass);
    }
  }
  if (max_freq2 <= 0.0f) return 0.0f;
  return 1.0f / (6.283185f * std::sqrt(max_freq2));
}

namespace {

// Records of 12 floats (VoxelConst, LinkConst) by member, widened to double (exact):
// result[j][i] = member j of record i.
template <class Record>
std::array<std::vector<double>, 12> members_of(const std::vector<Record>& records) {
  static_assert(sizeof(Record) == 12 * sizeof(float) && std::is_trivially_copyable_v<Record>);
  std::array<std::vector<double>, 12> members;
  for (auto& column : members) column.resize(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    float floats[12];
    std::memcpy(floats, &records[i], sizeof floats);
    for (int j = 0; j < 12; ++j) members[j][i] = floats[j];
  }
  return members;
}

}  // namespace

Model build_model(const BodyPlan& plan, const PhysicsConfig& cfg, const BuildOptions& options) {
  Model m;
  m.integrator = cfg.integrator;
  if (!(cfg.dt_fraction > 0.0) || !std::isfinite(cfg.dt_fraction))
    fail("physics.dt_fraction must be > 0");
  m.simd = resolve_simd(options.simd);
  if (!simd_supported(m.simd))
    fail(std::string("SIMD width ") + to_string(m.simd) + " is not supported by this CPU or build");
  const int nx = plan.lattice[0], ny = plan.lattice[1], nz = plan.lattice[2];
  if (nx <= 0 || ny <= 0 || nz <= 0) fail("body plan lattice must be positive in x, y and z");
  if (plan.cells.size() != static_cast<std::size_t>(nx) * ny * nz)
    fail("body plan has " + std::to_string(plan.cells.size()) + " cells, lattice needs " +
         std::to_string(static_cast<std::size_t>(nx) * ny * nz));
  if (!(plan.voxel_size > 0.0) || !std::isfinite(plan.voxel_size)) fail("voxel_size must be > 0");

  m.lattice = plan.lattice;
  // §1: the voxel size passes through a float (0.01 -> 0.009999999776482582).
  m.voxel_size = static_cast<double>(static_cast<float>(plan.voxel_size));
  m.rest_length = 0.5 * (m.voxel_size + m.voxel_size);
  m.inv_rest_length = 1.0 / m.rest_length;
  m.floor = cfg.floor;
  try {
    m.terrain = make_terrain(options.terrain, m.lattice, m.voxel_size);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  m.self_collision = cfg.self_collision;
  const double s = m.voxel_size;

  std::vector<VoxelMaterial> mats;
  mats.reserve(plan.materials.size());
  for (std::size_t k = 0; k < plan.materials.size(); ++k) {
    const auto& pm = plan.materials[k];
    if (!(pm.youngs_modulus > 0.0) || !(pm.density > 0.0))
      fail("material " + std::to_string(k + 1) + " needs youngs_modulus > 0 and density > 0");
    mats.push_back(make_voxel_material(pm, s, cfg));
  }

  // ---- voxels, insertion order x outer, y, z inner (§5 step 4) ------------------------------
  m.cell_to_voxel.assign(plan.cells.size(), -1);
  for (int x = 0; x < nx; ++x)
    for (int y = 0; y < ny; ++y)
      for (int z = 0; z < nz; ++z) {
        const int value = plan.cells[plan.cell_index(x, y, z)];
        if (value < 0)
          fail("cell (" + std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) +
               ") has negative value " + std::to_string(value));
        if (!BodyPlan::is_structural(value)) continue;
        if (static_cast<std::size_t>(value) > mats.size())
          fail("cell value " + std::to_string(value) + " names a material beyond the " +
               std::to_string(mats.size()) + " defined");
        m.cell_to_voxel[m.cell_index(x, y, z)] = static_cast<int>(m.voxel_cell.size());
        m.voxel_cell.push_back({x, y, z});
        m.voxel_material.push_back(value);
        m.voxel_const.push_back(mats[value - 1].c);
        m.voxel_mass.push_back(mats[value - 1].c.mass);
      }
  m.voxel_count = static_cast<int>(m.voxel_cell.size());
  const int nv = m.voxel_count;

  m.voxel_fixed.assign(nv, 0);
  for (const auto& c : options.fixed_cells) {
    if (c[0] < 0 || c[0] >= nx || c[1] < 0 || c[1] >= ny || c[2] < 0 || c[2] >= nz)
      fail("fixed cell outside the lattice");
    const int v = m.cell_to_voxel[m.cell_index(c[0], c[1], c[2])];
    if (v < 0) fail("fixed cell is not a structural voxel");
    m.voxel_fixed[v] = 1;
  }
  m.free_voxel_count = static_cast<int>(std::count(m.voxel_fixed.begin(), m.voxel_fixed.end(), 0));

  // ---- links, creation order of §2.1, numbered axis by axis ----------------------------------
  // For each new voxel, directions X+, X-, Y+, Y-, Z+, Z- if the neighbour already exists; with
  // x-outer insertion only X-, Y-, Z- neighbours exist. The link material of an unordered pair is
  // created once, with (new voxel's material, neighbour's material) of its first link.
  // Link ids: the x links in creation order, then the y links, then the z links, so that the link
  // pass (one axis at a time) walks contiguous id ranges. Links are independent within a pass and
  // every per-voxel sum runs in direction order, so the numbering does not change any result.
  struct NewLink {
    int neg, pos;
    LinkConst c;
  };
  std::map<std::pair<int, int>, LinkConst> link_mats;
  std::array<std::vector<NewLink>, 3> axis_links;
  // (axis, index within the axis) of the link in each direction of each voxel, or -1
  std::vector<std::array<std::pair<int, int>, 6>> dir_link(nv);
  for (auto& d : dir_link) d.fill({-1, -1});
  for (int v = 0; v < nv; ++v) {
    const auto [x, y, z] = m.voxel_cell[v];
    const int nb[3] = {x > 0 ? m.cell_to_voxel[m.cell_index(x - 1, y, z)] : -1,
                       y > 0 ? m.cell_to_voxel[m.cell_index(x, y - 1, z)] : -1,
                       z > 0 ? m.cell_to_voxel[m.cell_index(x, y, z - 1)] : -1};
    for (int a = 0; a < 3; ++a) {
      const int n = nb[a];
      if (n < 0) continue;
      const int mv = m.voxel_material[v], mn = m.voxel_material[n];
      const auto key = std::minmax(mv, mn);
      auto it = link_mats.find(key);
      if (it == link_mats.end())
        it = link_mats.emplace(key, make_link_const(mats[mv - 1].e, mats[mn - 1].e, s)).first;
      const std::pair<int, int> slot{a, static_cast<int>(axis_links[a].size())};
      axis_links[a].push_back({n, v, it->second});  // n: lower index along the axis
      dir_link[n][2 * a] = slot;                    // + direction of N
      dir_link[v][2 * a + 1] = slot;                // - direction of P
    }
  }
  for (int a = 0; a < 3; ++a) {
    m.axis_link_begin[a] = m.link_count;
    for (const NewLink& l : axis_links[a]) {
      m.link_neg.push_back(l.neg);
      m.link_pos.push_back(l.pos);
      m.link_axis.push_back(static_cast<Axis>(a));
      m.link_const.push_back(l.c);
      ++m.link_count;
    }
  }
  m.axis_link_begin[3] = m.link_count;
  m.voxel_const_members = members_of(m.voxel_const);
  m.link_const_members = members_of(m.link_const);
  m.voxel_surface.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    int count = 0;
    std::array<int, 6>& slots = m.voxel_load_slots.emplace_back();
    for (int d = 0; d < 6; ++d) {
      const auto [axis, index] = dir_link[v][d];
      if (axis < 0) {
        slots[d] = m.missing_load_slot();
        continue;
      }
      ++count;
      // even directions (X+, Y+, Z+): v is the negative end of that link
      slots[d] = (m.axis_link_begin[axis] + index) * 2 + (d & 1);
    }
    m.voxel_surface[v] = count < 6 ? 1 : 0;
    if (m.voxel_surface[v]) m.surface_voxels.push_back(v);
  }

  // ---- self-collision nearby lists (§2.10): BFS over links to depth 5 ------------------------
  m.nearby_mask.assign(static_cast<std::size_t>(nv) * 4, 0);
  {
    std::vector<int> depth(nv, -1), queue;
    queue.reserve(nv);
    for (int v : m.surface_voxels) {
      queue.clear();
      queue.push_back(v);
      depth[v] = 0;
      for (std::size_t head = 0; head < queue.size(); ++head) {
        const int u = queue[head];
        if (depth[u] == 5) continue;
        for (int slot : m.voxel_load_slots[u]) {
          if (slot == m.missing_load_slot()) continue;
          const int l = slot >> 1;
          const int w = (slot & 1) ? m.link_neg[l] : m.link_pos[l];
          if (depth[w] >= 0) continue;
          depth[w] = depth[u] + 1;
          queue.push_back(w);
        }
      }
      for (int u : queue) {
        if (u != v && m.voxel_surface[u]) {
          const auto& ca = m.voxel_cell[v];
          const auto& cb = m.voxel_cell[u];
          const int bit = nearby_bit_of_offset(cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2]);
          m.nearby_mask[static_cast<std::size_t>(v) * 4 + (bit >> 6)] |= std::uint64_t{1}
                                                                         << (bit & 63);
        }
        depth[u] = -1;
      }
    }
  }
  // Voxelyze: watch radius (2 * 0.75 + 1.0) voxels, recalc distance 1.0 / 2 voxels (float).
  m.collision_watch_radius = static_cast<float>(s * (2 * 0.75f + 1.0f));
  m.collision_recalc_distance = static_cast<float>(s * 1.0f / 2);

  // ---- time step (§2.14) x dt_fraction ----------------------------------------------------------
  const float rec = recommended_time_step(m);
  m.dt_f = static_cast<float>(static_cast<double>(rec) * cfg.dt_fraction);
  m.dt = m.dt_f;
  return m;
}

}  // namespace softevo::physics
