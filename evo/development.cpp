#include "evo/development.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

namespace softevo::evo {

namespace morph {

namespace {

std::size_t volume(const Dims& d) {
  return static_cast<std::size_t>(d[0]) * static_cast<std::size_t>(d[1]) *
         static_cast<std::size_t>(d[2]);
}

std::size_t at(const Dims& d, int x, int y, int z) {
  return (static_cast<std::size_t>(x) * static_cast<std::size_t>(d[1]) +
          static_cast<std::size_t>(y)) *
             static_cast<std::size_t>(d[2]) +
         static_cast<std::size_t>(z);
}

bool inside(const Dims& d, int x, int y, int z) {
  return x >= 0 && y >= 0 && z >= 0 && x < d[0] && y < d[1] && z < d[2];
}

void check(const Grid& a, const Dims& d, const char* what) {
  if (d[0] < 0 || d[1] < 0 || d[2] < 0 || a.size() != volume(d))
    throw std::invalid_argument(std::string(what) + ": grid size does not match its dimensions");
}

constexpr int kFace[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};

}  // namespace

Grid fill_holes(const Grid& a, const Dims& d) {
  // scipy.ndimage.binary_fill_holes: dilate the outside (border_value 1) through the background
  // with the default 6-connected structure; whatever it cannot reach is filled.
  check(a, d, "fill_holes");
  Grid reached(a.size(), 0);
  std::vector<std::array<int, 3>> stack;
  for (int x = 0; x < d[0]; ++x)
    for (int y = 0; y < d[1]; ++y)
      for (int z = 0; z < d[2]; ++z) {
        const bool border =
            x == 0 || y == 0 || z == 0 || x == d[0] - 1 || y == d[1] - 1 || z == d[2] - 1;
        const std::size_t i = at(d, x, y, z);
        if (border && !a[i] && !reached[i]) {
          reached[i] = 1;
          stack.push_back({x, y, z});
        }
      }
  while (!stack.empty()) {
    const auto p = stack.back();
    stack.pop_back();
    for (const auto& f : kFace) {
      const int x = p[0] + f[0], y = p[1] + f[1], z = p[2] + f[2];
      if (!inside(d, x, y, z)) continue;
      const std::size_t i = at(d, x, y, z);
      if (!a[i] && !reached[i]) {
        reached[i] = 1;
        stack.push_back({x, y, z});
      }
    }
  }
  Grid out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) out[i] = reached[i] ? 0 : 1;
  return out;
}

Grid erode26(const Grid& a, const Dims& d) {
  // scipy.ndimage.binary_erosion with a 3x3x3 structure and border_value 0.
  check(a, d, "erode26");
  Grid out(a.size(), 0);
  for (int x = 0; x < d[0]; ++x)
    for (int y = 0; y < d[1]; ++y)
      for (int z = 0; z < d[2]; ++z) {
        bool keep = true;
        for (int dx = -1; dx <= 1 && keep; ++dx)
          for (int dy = -1; dy <= 1 && keep; ++dy)
            for (int dz = -1; dz <= 1 && keep; ++dz)
              keep = inside(d, x + dx, y + dy, z + dz) && a[at(d, x + dx, y + dy, z + dz)];
        out[at(d, x, y, z)] = keep ? 1 : 0;
      }
  return out;
}

Grid dilate26(const Grid& a, const Dims& d) {
  // scipy.ndimage.binary_dilation with a 3x3x3 structure (outside contributes nothing).
  check(a, d, "dilate26");
  Grid out(a.size(), 0);
  for (int x = 0; x < d[0]; ++x)
    for (int y = 0; y < d[1]; ++y)
      for (int z = 0; z < d[2]; ++z) {
        if (!a[at(d, x, y, z)]) continue;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
              if (inside(d, x + dx, y + dy, z + dz)) out[at(d, x + dx, y + dy, z + dz)] = 1;
      }
  return out;
}

std::vector<int> label(const Grid& a, const Dims& d, int connectivity, int& count) {
  // scipy.ndimage.label numbering: components in order of their first cell in C order.
  check(a, d, "label");
  if (connectivity != 6 && connectivity != 26)
    throw std::invalid_argument("label: connectivity must be 6 or 26");
  std::vector<int> labels(a.size(), 0);
  count = 0;
  std::vector<std::array<int, 3>> stack;
  for (int x = 0; x < d[0]; ++x)
    for (int y = 0; y < d[1]; ++y)
      for (int z = 0; z < d[2]; ++z) {
        const std::size_t start = at(d, x, y, z);
        if (!a[start] || labels[start]) continue;
        labels[start] = ++count;
        stack.push_back({x, y, z});
        while (!stack.empty()) {
          const auto p = stack.back();
          stack.pop_back();
          for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dz = -1; dz <= 1; ++dz) {
                const int manhattan = std::abs(dx) + std::abs(dy) + std::abs(dz);
                if (manhattan == 0 || (connectivity == 6 && manhattan != 1)) continue;
                const int nx = p[0] + dx, ny = p[1] + dy, nz = p[2] + dz;
                if (!inside(d, nx, ny, nz)) continue;
                const std::size_t i = at(d, nx, ny, nz);
                if (a[i] && !labels[i]) {
                  labels[i] = count;
                  stack.push_back({nx, ny, nz});
                }
              }
        }
      }
  return labels;
}

double linspace01(int i, int n) {
  // numpy.linspace(0, 1, n): i * step + 0 with step = 1/(n-1); the last value is set to stop.
  if (n <= 1) return 0.0;
  if (i == n - 1) return 1.0;
  const double step = 1.0 / static_cast<double>(n - 1);
  return static_cast<double>(i) * step + 0.0;
}

int stiffness_bin(double s) {
  // §6.4: numpy.digitize(clip(s,-1,1), linspace(-1,1,10)) = number of edges <= s, edges
  // e_j = j*(2/9) + (-1) (numpy linspace arithmetic), e_9 = 1.0 exactly. numpy sorts NaN after
  // every number, so NaN lands in the top bin.
  if (std::isnan(s)) return 10;
  const double c = std::max(-1.0, std::min(1.0, s));
  const double step = 2.0 / 9.0;
  int bin = 0;
  for (int j = 0; j < 10; ++j) {
    const double edge = j == 9 ? 1.0 : static_cast<double>(j) * step + -1.0;
    if (edge <= c) bin = j + 1;
  }
  return bin;
}

long round_half_even(double v) {
  // Python 3 round(x): nearest integer, ties to even (std::nearbyint in the default rounding
  // mode FE_TONEAREST does exactly that).
  return static_cast<long>(std::nearbyint(v));
}

}  // namespace morph

namespace {

using morph::Dims;
using morph::Grid;

}  // namespace

DevelopedBody develop_body(const CppnGenome& genome, const BodyConfig& body) {
  if (body.lattice.size() != 3)
    throw std::invalid_argument("body.lattice: expected 3 sizes, got " +
                                std::to_string(body.lattice.size()));
  for (auto n : body.lattice)
    if (n < 1 || n > 1000)
      throw std::invalid_argument("body.lattice: size " + std::to_string(n) +
                                  " out of range [1, 1000]");
  const Dims dims{static_cast<int>(body.lattice[0]), static_cast<int>(body.lattice[1]),
                  static_cast<int>(body.lattice[2])};
  const std::size_t cells = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  if (cells > 10'000'000) throw std::invalid_argument("body.lattice: more than 1e7 cells");
  const bool pneuvox_distance = body.distance_input == DistanceInput::pneuvox;
  if (body.max_chambers < 0 || body.max_chambers > 10)
    throw std::invalid_argument("body.max_chambers: " + std::to_string(body.max_chambers) +
                                " out of range [0, 10] (chamber ids are 11..20)");
  if (genome.num_inputs != 4 || genome.num_outputs != 4)
    throw std::invalid_argument("develop_body: the CPPN must have 4 inputs and 4 outputs");

  FeedForwardNetwork net(genome);
  auto idx = [&](int x, int y, int z) {
    return (static_cast<std::size_t>(x) * dims[1] + y) * dims[2] + z;
  };

  // §6.2-6.4: query every lattice cell. V = material (0 empty), P = pneumatic, plus the stiffness
  // bin (step 5 re-queries the CPPN: same value) and the sorting output of every cell.
  std::vector<int> V(cells, 0), stiffness(cells, 0);
  std::vector<double> sorting(cells, 0.0);
  Grid P(cells, 0);
  // §6.2 "pneuvox": the point (bx/2, by/2, bz/2) = (5,5,5) in normalised coordinates (Python 3
  // true division); "center": the lattice centre (0.5, 0.5, 0.5).
  const std::array<double, 3> centre =
      pneuvox_distance ? std::array<double, 3>{dims[0] / 2.0, dims[1] / 2.0, dims[2] / 2.0}
                       : std::array<double, 3>{0.5, 0.5, 0.5};
  std::array<double, 4> in{};
  std::array<double, 4> out{};
  for (int x = 0; x < dims[0]; ++x)
    for (int y = 0; y < dims[1]; ++y)
      for (int z = 0; z < dims[2]; ++z) {
        in[0] = morph::linspace01(x, dims[0]);
        in[1] = morph::linspace01(y, dims[1]);
        in[2] = morph::linspace01(z, dims[2]);
        const double dx = in[0] - centre[0], dy = in[1] - centre[1], dz = in[2] - centre[2];
        in[3] = std::sqrt(dx * dx + dy * dy + dz * dz);  // d = |(x,y,z) - centre|
        net.activate(in, out);
        const std::size_t i = idx(x, y, z);
        // §6.3: output 0 = presence, 1 = is_pneu, 2 = stiffness, 3 = sorting.
        stiffness[i] = morph::stiffness_bin(out[2]);
        sorting[i] = out[3];
        if (out[0] > body.presence_threshold) {
          if (out[1] > body.pneumatic_threshold)
            P[i] = 1;  // pneumatic cell, V stays 0
          else
            V[i] = stiffness[i];
        }
      }

  DevelopedBody result;
  // §6.5 step 1: no structural cell -> invalid.
  Grid solid(cells);
  for (std::size_t i = 0; i < cells; ++i) solid[i] = V[i] != 0;
  if (std::none_of(solid.begin(), solid.end(), [](std::uint8_t v) { return v != 0; }))
    return result;
  result.valid = true;

  // Step 2: enclosed empty space becomes pneumatic: H = fill_holes(V!=0) and not (V!=0).
  const Grid filled = morph::fill_holes(solid, dims);
  for (std::size_t i = 0; i < cells; ++i)
    if (filled[i] && !solid[i]) P[i] = 1;
  // Step 3: cells enclosed by pneumatic cells become pneumatic (in P only).
  P = morph::fill_holes(P, dims);
  // Step 4: remove the outer layer and thin pneumatic regions.
  P = morph::erode26(P, dims);
  // Step 5: the shell around P becomes structural with the cell's own stiffness bin.
  const Grid dilated = morph::dilate26(P, dims);
  for (std::size_t i = 0; i < cells; ++i)
    if (dilated[i] && !P[i]) V[i] = stiffness[i];

  // Step 6: keep the largest face-connected component (ties -> lowest label) and its holes.
  for (std::size_t i = 0; i < cells; ++i) solid[i] = V[i] != 0;
  int count = 0;
  const std::vector<int> labels = morph::label(solid, dims, 6, count);
  std::vector<std::size_t> areas(static_cast<std::size_t>(count) + 1, 0);
  for (int l : labels)
    if (l > 0) ++areas[static_cast<std::size_t>(l)];
  int best = 1;
  for (int l = 2; l <= count; ++l)
    if (areas[static_cast<std::size_t>(l)] > areas[static_cast<std::size_t>(best)]) best = l;
  Grid component(cells);
  for (std::size_t i = 0; i < cells; ++i) component[i] = labels[i] == best;
  const Grid mask = morph::fill_holes(component, dims);
  for (std::size_t i = 0; i < cells; ++i) {
    if (!mask[i]) {
      V[i] = 0;
      P[i] = 0;
    }
  }

  // Step 7: trim V, P and the sorting grid to the bounding box of the mask.
  std::array<int, 3> lo{dims[0], dims[1], dims[2]}, hi{-1, -1, -1};
  for (int x = 0; x < dims[0]; ++x)
    for (int y = 0; y < dims[1]; ++y)
      for (int z = 0; z < dims[2]; ++z)
        if (mask[idx(x, y, z)]) {
          const std::array<int, 3> p{x, y, z};
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
          }
        }
  const Dims tdims{hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  const std::size_t tcells = static_cast<std::size_t>(tdims[0]) * tdims[1] * tdims[2];
  BodyPlan& plan = result.plan;
  plan.lattice = tdims;
  plan.cells.assign(tcells, 0);
  Grid tP(tcells, 0);
  std::vector<double> tsorting(tcells, 0.0);
  for (int x = 0; x < tdims[0]; ++x)
    for (int y = 0; y < tdims[1]; ++y)
      for (int z = 0; z < tdims[2]; ++z) {
        const std::size_t src = idx(x + lo[0], y + lo[1], z + lo[2]);
        const std::size_t dst = plan.cell_index(x, y, z);
        plan.cells[dst] = V[src];
        tP[dst] = P[src];
        tsorting[dst] = sorting[src];
      }

  // Step 8: chambers = 26-connected blobs of P, sorted by the sorting output at the rounded
  // centroid (Python round: half to even), stable.
  int blobs = 0;
  const std::vector<int> blob_of = morph::label(tP, tdims, 26, blobs);
  struct Blob {
    int label;
    double key;
  };
  std::vector<Blob> order;
  {
    std::vector<std::array<double, 3>> sum(static_cast<std::size_t>(blobs) + 1, {0, 0, 0});
    std::vector<double> n(static_cast<std::size_t>(blobs) + 1, 0.0);
    for (int x = 0; x < tdims[0]; ++x)
      for (int y = 0; y < tdims[1]; ++y)
        for (int z = 0; z < tdims[2]; ++z) {
          const int l = blob_of[plan.cell_index(x, y, z)];
          if (l == 0) continue;
          auto& s = sum[static_cast<std::size_t>(l)];
          s[0] += x;  // integer sums are exact in double, so the mean is correctly rounded
          s[1] += y;
          s[2] += z;
          n[static_cast<std::size_t>(l)] += 1.0;
        }
    for (int l = 1; l <= blobs; ++l) {
      const auto& s = sum[static_cast<std::size_t>(l)];
      const double cnt = n[static_cast<std::size_t>(l)];
      const int cx = static_cast<int>(morph::round_half_even(s[0] / cnt));
      const int cy = static_cast<int>(morph::round_half_even(s[1] / cnt));
      const int cz = static_cast<int>(morph::round_half_even(s[2] / cnt));
      order.push_back(Blob{l, tsorting[plan.cell_index(cx, cy, cz)]});
    }
  }
  // Ascending; NaN keys (never seen in practice) sort last to keep a strict weak ordering.
  std::stable_sort(order.begin(), order.end(), [](const Blob& a, const Blob& b) {
    if (std::isnan(a.key)) return false;
    if (std::isnan(b.key)) return true;
    return a.key < b.key;
  });

  // Step 9: the first min(n, max_chambers) blobs get ids 11, 12, ... (overwriting floating
  // structural cells inside the cavity); the rest stay as they are in V.
  const int chambers = std::min(blobs, static_cast<int>(body.max_chambers));
  std::vector<int> chamber_of_label(static_cast<std::size_t>(blobs) + 1, -1);
  for (int q = 0; q < chambers; ++q)
    chamber_of_label[static_cast<std::size_t>(order[static_cast<std::size_t>(q)].label)] = q;
  for (std::size_t i = 0; i < tcells; ++i) {
    const int q = chamber_of_label[static_cast<std::size_t>(blob_of[i])];
    if (blob_of[i] > 0 && q >= 0) plan.cells[i] = kFirstChamberCell + q;
  }
  // Step 10.
  result.chamber_count = chambers;
  result.actuatable = chambers > 0;
  return result;
}

}  // namespace softevo::evo
