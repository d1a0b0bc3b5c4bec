// §2.10 self-collision broadphase: the pairs of surface voxels close enough to touch, found
// through a hashed uniform grid, in the reference's order. Internal to physics/ (collision.hpp).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "physics/collision.hpp"

namespace softevo::physics {
namespace {

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

}  // namespace

// §2.10 pair rebuild. Same pairs, in the same order, as the reference's O(N^2) scan: for each
// surface voxel a in list order, every later surface voxel b with |pos_a - pos_b|^2 <= (2.5 s)^2
// that is not within 5 link hops. Found here through a uniform grid of cell size 2.5 s (a pair
// within the radius lies in the same or neighbouring cells), its cells hashed into a fixed number
// of buckets: each pair of neighbouring cells is tested once, then the pairs are sorted into the
// reference's order.
void rebuild_collision_pairs(const Model& m, State& st, Scratch& sc) {
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

}  // namespace softevo::physics
