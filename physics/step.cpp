// One physics time step: the public step(), the self-collision pass (§2.10, scalar) and the
// choice of SIMD width. The link and voxel passes are in physics/step_kernels.hpp, built here for
// SSE2 (2 lanes) and in step_avx2.cpp / step_avx512.cpp for 4 lanes; all widths give
// bit-identical results (see step_kernels.hpp).
//
// Precision: state is double; constants are float (Model); products the reference forms in float
// (collision forces) are formed in float here too. The build uses -ffp-contract=off, so the
// written operation order is the executed one.
#include "physics/step.hpp"

// The passes use SSE2 (part of every x86-64 CPU). Other architectures would need a scalar build
// of the lane traits below (the scalar per-lane code is already there).
#if !defined(__SSE2__)
#error "softevo physics needs an x86-64 (SSE2) target; see the note at the top of step.cpp"
#endif
#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <string>

#include "physics/step_kernels.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

const char* to_string(StepStatus status) {
  switch (status) {
    case StepStatus::ok:
      return "ok";
    case StepStatus::diverged:
      return "diverged";
    case StepStatus::non_finite:
      return "non_finite";
  }
  return "unknown";
}

Scratch make_scratch(const Model& model) {
  Scratch sc;
  const std::size_t nl = model.link_count, nv = model.voxel_count;
  sc.link_end_load.assign(model.missing_load_slot() + 1,
                          Scratch::EndLoad{Vec3::Zero(), Vec3::Zero()});
  sc.link_list_small.assign(nl, 0);
  sc.link_list_large.assign(nl, 0);
  sc.link_damping_neg.assign(nl, 0.0);
  sc.link_damping_pos.assign(nl, 0.0);
  sc.collision_force.assign(nv, Vec3::Zero());
  sc.part2_force.assign(nv, Vec3::Zero());
  sc.fric.assign(nv, Vec3::Zero());
  sc.old_pos.assign(nv, Vec3::Zero());
  const std::size_t ns = model.surface_voxels.size();
  std::size_t buckets = 1;
  while (buckets < 2 * ns + 2) buckets <<= 1;
  sc.grid_entries.assign(ns, Scratch::GridEntry{});
  sc.grid_sorted.assign(ns, Scratch::GridEntry{});
  sc.grid_bucket_begin.assign(buckets + 1, 0);
  sc.candidates.assign(ns, 0);
  return sc;
}

namespace {

// SSE2 lane traits of step_kernels.hpp: 2 doubles per vector.
struct LanesSse2 {
  static constexpr int W = 2;
  using D = double __attribute__((vector_size(16)));
  using M = long long __attribute__((vector_size(16)));
  static D round_to_float(D x) { return _mm_cvtps_pd(_mm_cvtpd_ps(x)); }
  static D sqrt(D x) { return _mm_sqrt_pd(x); }
  static int bits(M m) { return _mm_movemask_pd(reinterpret_cast<__m128d>(m)); }
  // Lane k of (x, y, z) as the floats (x_k, y_k, z_k, 0), k = 0..1 (round to nearest).
  static void float_rows(D x, D y, D z, __m128 (&rows)[2]) {
    const __m128 xy = _mm_unpacklo_ps(_mm_cvtpd_ps(x), _mm_cvtpd_ps(y));   // x0 y0 x1 y1
    const __m128 z0 = _mm_unpacklo_ps(_mm_cvtpd_ps(z), _mm_setzero_ps());  // z0 0 z1 0
    rows[0] = _mm_movelh_ps(xy, z0);
    rows[1] = _mm_movehl_ps(z0, xy);
  }
  // Transposing record loads / stores (see step_kernels.hpp).
  static void gather3(const double* const* p, D& x, D& y, D& z) {
    const __m128d r0 = _mm_loadu_pd(p[0]), r1 = _mm_loadu_pd(p[1]);
    x = _mm_unpacklo_pd(r0, r1);
    y = _mm_unpackhi_pd(r0, r1);
    z = _mm_loadh_pd(_mm_load_sd(p[0] + 2), p[1] + 2);
  }
  static void gather4(const double* const* p, D& w, D& x, D& y, D& z) {
    const __m128d a0 = _mm_loadu_pd(p[0]), a1 = _mm_loadu_pd(p[1]);
    const __m128d b0 = _mm_loadu_pd(p[0] + 2), b1 = _mm_loadu_pd(p[1] + 2);
    w = _mm_unpacklo_pd(a0, a1);
    x = _mm_unpackhi_pd(a0, a1);
    y = _mm_unpacklo_pd(b0, b1);
    z = _mm_unpackhi_pd(b0, b1);
  }
  static void scatter3(double* const* p, D x, D y, D z, int mask) {
    if (mask & 1) {
      _mm_storeu_pd(p[0], _mm_unpacklo_pd(x, y));
      _mm_store_sd(p[0] + 2, z);
    }
    if (mask & 2) {
      _mm_storeu_pd(p[1], _mm_unpackhi_pd(x, y));
      _mm_storeh_pd(p[1] + 2, z);
    }
  }
  // W = 2 consecutive records of N doubles at p <-> N lanes (lane k = record k).
  template <int N>
  static void load_records(const double* p, D (&c)[N]) {
    if constexpr (N == 3) {  // x0 y0 | z0 x1 | y1 z1
      const __m128d r0 = _mm_loadu_pd(p), r1 = _mm_loadu_pd(p + 2), r2 = _mm_loadu_pd(p + 4);
      c[0] = _mm_shuffle_pd(r0, r1, 0b10);
      c[1] = _mm_shuffle_pd(r0, r2, 0b01);
      c[2] = _mm_shuffle_pd(r1, r2, 0b10);
    } else {
      static_assert(N % 2 == 0);
      for (int j = 0; j < N; j += 2) {
        const __m128d r0 = _mm_loadu_pd(p + j), r1 = _mm_loadu_pd(p + N + j);
        c[j] = _mm_unpacklo_pd(r0, r1);
        c[j + 1] = _mm_unpackhi_pd(r0, r1);
      }
    }
  }
  template <int N>
  static void store_records(const D (&c)[N], double* p) {
    if constexpr (N == 3) {
      _mm_storeu_pd(p, _mm_unpacklo_pd(c[0], c[1]));
      _mm_storeu_pd(p + 2, _mm_shuffle_pd(c[2], c[0], 0b10));
      _mm_storeu_pd(p + 4, _mm_unpackhi_pd(c[1], c[2]));
    } else {
      static_assert(N % 2 == 0);
      for (int j = 0; j < N; j += 2) {
        _mm_storeu_pd(p + j, _mm_unpacklo_pd(c[j], c[j + 1]));
        _mm_storeu_pd(p + N + j, _mm_unpackhi_pd(c[j], c[j + 1]));
      }
    }
  }
  static void gather_f12(const float* const* p, D (&out)[12]) {
    for (int b = 0; b < 3; ++b) {
      const __m128 va = _mm_loadu_ps(p[0] + 4 * b), vb = _mm_loadu_ps(p[1] + 4 * b);
      const __m128 lo = _mm_unpacklo_ps(va, vb), hi = _mm_unpackhi_ps(va, vb);
      out[4 * b] = _mm_cvtps_pd(lo);
      out[4 * b + 1] = _mm_cvtps_pd(_mm_movehl_ps(lo, lo));
      out[4 * b + 2] = _mm_cvtps_pd(hi);
      out[4 * b + 3] = _mm_cvtps_pd(_mm_movehl_ps(hi, hi));
    }
  }
};

inline int cell_coord(double x, double inv_h) {
  const double c = std::floor(x * inv_h);
  if (!(c > -1.0e9)) return -1000000000;  // also catches NaN
  if (c > 1.0e9) return 1000000000;
  return static_cast<int>(c);
}

inline std::size_t bucket_of(int cx, int cy, int cz, std::size_t mask) {
  const std::uint64_t h = static_cast<std::uint64_t>(static_cast<std::uint32_t>(cx)) * 73856093u ^
                          static_cast<std::uint64_t>(static_cast<std::uint32_t>(cy)) * 19349663u ^
                          static_cast<std::uint64_t>(static_cast<std::uint32_t>(cz)) * 83492791u;
  return static_cast<std::size_t>(h) & mask;
}

// The 13 lattice offsets (dx, dy, dz) > (0, 0, 0) in lexicographic order: with the cell itself,
// every unordered pair of neighbouring grid cells is visited exactly once.
constexpr int kHalfShell[13][3] = {{0, 0, 1},  {0, 1, -1}, {0, 1, 0},  {0, 1, 1}, {1, -1, -1},
                                   {1, -1, 0}, {1, -1, 1}, {1, 0, -1}, {1, 0, 0}, {1, 0, 1},
                                   {1, 1, -1}, {1, 1, 0},  {1, 1, 1}};

// §2.10 pair rebuild. Same pairs, in the same order, as the reference's O(N^2) scan: for each
// surface voxel a in list order, every later surface voxel b with |pos_a - pos_b|^2 <= (2.5 s)^2
// that is not within 5 link hops. Found here through a uniform grid of cell size 2.5 s (a pair
// within the radius lies in the same or neighbouring cells), its cells hashed into a fixed number
// of buckets: each pair of neighbouring cells is tested once, then the pairs are sorted into the
// reference's order.
void rebuild_pairs(const Model& m, State& st, Scratch& sc) {
  const auto& surf = m.surface_voxels;
  const int ns = static_cast<int>(surf.size());
  const float radius = static_cast<float>(m.collision_watch_radius);
  const float thresh_sq = radius * radius;  // float, as Voxelyze's threshRadiusSq
  const double inv_h = 1.0 / static_cast<double>(radius);
  const int buckets = static_cast<int>(sc.grid_bucket_begin.size()) - 1;
  const std::size_t mask = static_cast<std::size_t>(buckets) - 1;
  std::vector<int>& begin = sc.grid_bucket_begin;
  std::vector<Scratch::GridEntry>& entries = sc.grid_entries;

  // 1. Counting sort of the surface voxels by bucket: count, running sums (= bucket ends), then
  //    place the slots in descending order at descending positions, which leaves begin[b] at the
  //    start of bucket b. A bucket holding several cells (hash collision, rare) is then put in
  //    cell order, so that each cell is one run of entries.
  std::fill(begin.begin(), begin.end(), 0);
  for (int si = 0; si < ns; ++si) {
    const Vec3& p = st.pos[surf[si]];
    // Voxelyze: lastColWatchPosition = (Vec3D<float>)pos for every non-interior voxel
    st.col_watch_pos[surf[si]] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(p.z())};
    const int cx = cell_coord(p.x(), inv_h), cy = cell_coord(p.y(), inv_h),
              cz = cell_coord(p.z(), inv_h);
    ++begin[bucket_of(cx, cy, cz, mask)];
    entries[si] = Scratch::GridEntry{p.x(), p.y(), p.z(), si, cx, cy, cz};  // staged unsorted
  }
  int running = 0;
  for (int b = 0; b <= buckets; ++b) {
    running += begin[b];
    begin[b] = running;
  }
  // (grid_entries is in slot order; grid_sorted receives the bucket order)
  std::vector<Scratch::GridEntry>& sorted = sc.grid_sorted;
  for (int si = ns - 1; si >= 0; --si) {
    const Scratch::GridEntry& e = entries[si];
    sorted[--begin[bucket_of(e.cx, e.cy, e.cz, mask)]] = e;
  }
  const auto same_cell = [](const Scratch::GridEntry& e, int x, int y, int z) {
    return e.cx == x && e.cy == y && e.cz == z;
  };
  const auto cell_less = [](const Scratch::GridEntry& e, const Scratch::GridEntry& f) {
    return e.cx != f.cx ? e.cx < f.cx : e.cy != f.cy ? e.cy < f.cy : e.cz < f.cz;
  };
  for (int b = 0; b < buckets; ++b) {
    const auto first = sorted.begin() + begin[b], last = sorted.begin() + begin[b + 1];
    for (auto e = first; e != last; ++e)
      if (!same_cell(*e, first->cx, first->cy, first->cz)) {
        // insertion sort: stable (keeps slot order within a cell) and allocation-free
        for (auto x = first + 1; x != last; ++x)
          for (auto y = x; y != first && cell_less(*y, *(y - 1)); --y) std::iter_swap(y, y - 1);
        break;
      }
  }

  // 2. Every pair of entries in the same cell or in two neighbouring cells, once: the entries of
  //    cell c = run [r0, r1) of its bucket; partner cell q = run of q's bucket with cell q.
  int count = 0;
  auto add_pair = [&](int a, int b) {  // voxel ids, a < b
    if (count == static_cast<int>(st.col_pairs.size())) {
      // pathological pile-up beyond the reserved slots: grow (the only allocation in a step)
      st.col_pairs.resize(st.col_pairs.size() * 2 + 64);
      ++st.counters.collision_pair_growths;
    }
    st.col_pairs[count++] = CollisionPair{a, b};
  };
  // test entry i against the entries [j0, j1): distance first (branch-free, into candidates),
  // then the nearby list for the few within the radius
  auto test_against = [&](const Scratch::GridEntry& ei, int j0, int j1) {
    int* within = sc.candidates.data();
    int n = 0;
    for (int j = j0; j < j1; ++j) {
      const Scratch::GridEntry& ej = sorted[j];
      const double ex = ei.x - ej.x, ey = ei.y - ej.y, ez = ei.z - ej.z;
      within[n] = j;
      n += (ex * ex + ey * ey + ez * ez > thresh_sq) ? 0 : 1;
    }
    for (int k = 0; k < n; ++k) {
      const int sj = sorted[within[k]].slot;
      const int a = surf[std::min(ei.slot, sj)], b = surf[std::max(ei.slot, sj)];
      if (!is_nearby(m, a, b)) add_pair(a, b);
    }
  };
  for (int b = 0; b < buckets; ++b) {
    for (int r0 = begin[b]; r0 < begin[b + 1];) {
      const Scratch::GridEntry& head = sorted[r0];
      int r1 = r0 + 1;
      while (r1 < begin[b + 1] && same_cell(sorted[r1], head.cx, head.cy, head.cz)) ++r1;
      for (int i = r0; i < r1; ++i) test_against(sorted[i], i + 1, r1);  // within the cell
      for (const auto& off : kHalfShell) {
        const int qx = head.cx + off[0], qy = head.cy + off[1], qz = head.cz + off[2];
        const std::size_t qb = bucket_of(qx, qy, qz, mask);
        int q0 = begin[qb];
        const int q_end = begin[qb + 1];
        while (q0 < q_end && !same_cell(sorted[q0], qx, qy, qz)) ++q0;
        if (q0 == q_end) continue;  // cell q holds no surface voxel
        int q1 = q0 + 1;
        while (q1 < q_end && same_cell(sorted[q1], qx, qy, qz)) ++q1;
        for (int i = r0; i < r1; ++i) test_against(sorted[i], q0, q1);
      }
      r0 = r1;
    }
  }

  // 3. The reference's creation order: ascending a, then ascending partner b (voxel ids ascend
  //    with the slots, and each pair has a < b).
  std::sort(st.col_pairs.begin(), st.col_pairs.begin() + count,
            [](const CollisionPair& x, const CollisionPair& y) {
              return x.a != y.a ? x.a < y.a : x.b < y.b;
            });
  st.col_pair_count = count;
  st.collisions_stale = false;
  ++st.counters.collision_rebuilds;
}

// §2.10: staleness check, rebuild if stale, pair forces -> collision_force (collisionF of §2.7).
[[gnu::noinline]] void update_collisions(const Model& m, State& st, Scratch& sc) {
  if (!st.collisions_stale) {
    const float rd = static_cast<float>(m.collision_recalc_distance);
    const float rd_sq = rd * rd;
    for (int v : m.surface_voxels) {
      const Vec3& p = st.pos[v];
      const auto& w = st.col_watch_pos[v];
      const double ex = p.x() - w[0], ey = p.y() - w[1], ez = p.z() - w[2];
      if (ex * ex + ey * ey + ez * ez > rd_sq) {
        st.collisions_stale = true;
        break;
      }
    }
  }
  if (st.collisions_stale) rebuild_pairs(m, st, sc);

  if (!sc.collision_force_zero) {
    std::fill(sc.collision_force.begin(), sc.collision_force.end(), Vec3::Zero());
    sc.collision_force_zero = true;
  }
  // D0 = (s + s) * 0.625 (sum of the two base sizes x envelope radius), float
  const float nom_dist = static_cast<float>((m.voxel_size + m.voxel_size) * 0.625f);
  for (int k = 0; k < st.col_pair_count; ++k) {
    const int a = st.col_pairs[k].a, b = st.col_pairs[k].b;
    const Vec3& p1 = st.pos[a];
    const Vec3& p2 = st.pos[b];
    const float ox = static_cast<float>(p2.x() - p1.x()), oy = static_cast<float>(p2.y() - p1.y()),
                oz = static_cast<float>(p2.z() - p1.z());
    const float len = std::sqrt(ox * ox + oy * oy + oz * oz);
    const float rel_dist = nom_dist - len;  // overlap, > 0 when touching
    if (!(rel_dist > 0)) continue;          // F = 0
    const float ux = ox / len, uy = oy / len, uz = oz / len;
    const VoxelConst& c1 = m.voxel_const[a];
    const VoxelConst& c2 = m.voxel_const[b];
    // k_c = harmonic mean of the k_pen, c_c = mean of C_col (float)
    const float kc = 2.0f / (1.0f / c1.k_pen + 1.0f / c2.k_pen);
    const float cc = 0.5f * (c1.c_col + c2.c_col);
    const Vec3& m1 = st.lin_mom[a];
    const Vec3& m2 = st.lin_mom[b];
    const double v1x = m1.x() * c1.inv_mass, v1y = m1.y() * c1.inv_mass, v1z = m1.z() * c1.inv_mass;
    const double v2x = m2.x() * c2.inv_mass, v2y = m2.y() * c2.inv_mass, v2z = m2.z() * c2.inv_mass;
    const double dux = ux, duy = uy, duz = uz;
    // v_rel = v1.n - v2.n (positive = approaching), float
    const float rel_vel = static_cast<float>((v1x * dux + v1y * duy + v1z * duz) -
                                             (v2x * dux + v2y * duy + v2z * duz));
    const float mag = kc * rel_dist + cc * rel_vel;
    const float fx = ux * mag, fy = uy * mag, fz = uz * mag;
    // voxel 1 receives -F, voxel 2 receives +F (collisionF = -sum of contactForce)
    sc.collision_force_zero = false;
    sc.collision_force[a] -= Vec3(fx, fy, fz);
    sc.collision_force[b] -= Vec3(-fx, -fy, -fz);
  }
}

}  // namespace

const StepKernels& step_kernels_sse2() {
  static constexpr StepKernels kernels = make_step_kernels<LanesSse2>(Simd::sse2);
  return kernels;
}

const char* to_string(Simd simd) {
  switch (simd) {
    case Simd::best:
      return "best";
    case Simd::sse2:
      return "sse2";
    case Simd::avx2:
      return "avx2";
    case Simd::avx512:
      return "avx512";
  }
  return "unknown";
}

namespace {
constexpr Simd kEverySimd[] = {Simd::best, Simd::sse2, Simd::avx2, Simd::avx512};
}

std::optional<Simd> parse_simd(std::string_view name) {
  for (Simd s : kEverySimd)
    if (name == to_string(s)) return s;
  return std::nullopt;
}

std::vector<std::string> simd_names() {
  std::vector<std::string> names;
  for (Simd s : kEverySimd) names.emplace_back(to_string(s));
  return names;
}

bool simd_supported(Simd simd) {
  switch (simd) {
    case Simd::best:
    case Simd::sse2:
      return true;
    case Simd::avx2:
#if defined(SOFTEVO_HAVE_AVX2_KERNELS)
      return __builtin_cpu_supports("avx2");
#else
      return false;
#endif
    case Simd::avx512:
#if defined(SOFTEVO_HAVE_AVX512_KERNELS)
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("avx512f") &&
             __builtin_cpu_supports("avx512vl");
#else
      return false;
#endif
  }
  return false;
}

Simd best_simd() {
  for (Simd s : {Simd::avx512, Simd::avx2})
    if (simd_supported(s)) return s;
  return Simd::sse2;
}

Simd resolve_simd(Simd simd) {
  return simd == Simd::best ? best_simd() : simd;
}

const StepKernels& step_kernels(Simd simd) {
  switch (resolve_simd(simd)) {
#if defined(SOFTEVO_HAVE_AVX2_KERNELS)
    case Simd::avx2:
      return step_kernels_avx2();
#endif
#if defined(SOFTEVO_HAVE_AVX512_KERNELS)
    case Simd::avx512:
      return step_kernels_avx512();
#endif
    default:
      return step_kernels_sse2();
  }
}

StepStatus step(const Model& model, State& state, Scratch& scratch,
                std::span<const Vec3> external_force) {
  if (!external_force.empty() &&
      external_force.size() != static_cast<std::size_t>(model.voxel_count))
    throw std::invalid_argument("physics::step: external_force has " +
                                std::to_string(external_force.size()) + " entries, model has " +
                                std::to_string(model.voxel_count) + " voxels");
  const StepKernels& kernels = step_kernels(model.simd);
  // 1. link pass; strain > 100 -> nothing else advances. The pneuvox step's mid-step link pass
  //    (§2.12 step 6) overwrites pos2, the angles and the strain before anything reads them, so
  //    its first pass leaves them out, and stores them only for a refused step.
  const bool pneuvox = model.integrator == Integrator::pneuvox;
  if (pneuvox ? kernels.link_pass_forces_only(model, state, scratch)
              : kernels.link_pass_forces(model, state, scratch)) {
    if (pneuvox) kernels.link_pass_restore_state(model, state, scratch);
    ++state.counters.diverged_steps;
    return StepStatus::diverged;
  }
  // 2. collisions
  if (model.self_collision) update_collisions(model, state, scratch);
  const bool finite = pneuvox
                          ? kernels.fork_voxel_passes(model, state, scratch, external_force)
                          : kernels.symplectic_voxel_pass(model, state, scratch, external_force);
  state.time += model.dt_f;  // 9.
  if (!finite) {
    ++state.counters.non_finite_steps;
    return StepStatus::non_finite;
  }
  ++state.counters.steps;
  return StepStatus::ok;
}

}  // namespace softevo::physics
