// The two-part casting mold and its cores on the fabrication grid (fabricate.hpp,
// docs/fabrication.md "Mold").
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "fabricate/fabricate.hpp"

namespace softevo::fabricate {

namespace {

// Boxes that share more than a face.
bool overlap(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  return (a.min().array() < b.max().array()).all() && (b.min().array() < a.max().array()).all();
}

// Millimetres to the nanometre: 50 mm rather than 49.99999999999999 from 5 x 0.01 m.
double mm_rounded(double metres) {
  return std::round(metres * 1e9) / 1e6;
}

nlohmann::ordered_json box_json(const Eigen::AlignedBox3d& b) {
  nlohmann::ordered_json lo = nlohmann::ordered_json::array(), hi = lo;
  for (int a = 0; a < 3; ++a) {
    lo.push_back(mm_rounded(b.min()[a]));
    hi.push_back(mm_rounded(b.max()[a]));
  }
  return {{"min_mm", lo}, {"max_mm", hi}};
}

}  // namespace

Mold make_mold(const Fabrication& fab) {
  const double s = fab.voxel_size;
  const double w = fab.options.wall;
  const Eigen::Vector3i& n = fab.lattice;
  auto lattice_label = [&](int x, int y, int z) {
    return fab.lattice_labels[(static_cast<std::size_t>(x) * n.y() + y) * n.z() + z];
  };
  Mold mold;
  mold.box = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-w),
                                 n.cast<double>() * s + Eigen::Vector3d::Constant(w));
  // Split: the widest horizontal section, halfway up its layer (ties: the lowest), or --split.
  std::vector<int> area(static_cast<std::size_t>(n.z()), 0);
  for (int x = 0; x < n.x(); ++x) {
    for (int y = 0; y < n.y(); ++y) {
      for (int z = 0; z < n.z(); ++z) area[z] += lattice_label(x, y, z) != label::kOutside;
    }
  }
  if (fab.options.split_z) {
    const double z = *fab.options.split_z;
    const int layer = static_cast<int>(std::floor(z / s));
    if (!(z > 0 && z < n.z() * s) || area[layer] == 0)
      throw FabricateError("fabricate: --split z=" + mm_text(z) +
                           " is outside the body (it must cut the body, between 0 and " +
                           mm_text(n.z() * s) + " above its bottom)");
    mold.split_z = z;
  } else {
    const int widest = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
    mold.split_z = (widest + 0.5) * s;
  }

  // Pins: each inlet channel runs on through the mold wall to the box, holding its core.
  std::vector<Eigen::AlignedBox3d> pins;
  for (const Inlet& inlet : fab.inlets) {
    Eigen::AlignedBox3d pin = inlet.box;
    const int a = inlet.face / 2;
    if (inlet.face % 2 == 0) {
      pin.min()[a] = inlet.box.max()[a];
      pin.max()[a] = mold.box.max()[a];
    } else {
      pin.max()[a] = inlet.box.min()[a];
      pin.min()[a] = mold.box.min()[a];
    }
    pins.push_back(pin);
  }
  auto column_box = [&](int x, int y, int top, double side) {
    const Eigen::Vector3d c((x + 0.5) * s, (y + 0.5) * s, 0);
    return Eigen::AlignedBox3d(
        Eigen::Vector3d(c.x() - side / 2, c.y() - side / 2, (top + 1) * s),
        Eigen::Vector3d(c.x() + side / 2, c.y() + side / 2, mold.box.max().z()));
  };
  auto free_of_pins = [&](const Eigen::AlignedBox3d& b) {
    return std::none_of(pins.begin(), pins.end(),
                        [&](const Eigen::AlignedBox3d& p) { return overlap(p, b); });
  };
  // Column tops: the highest non-air cell of each (x, y), -1 for an empty column.
  std::vector<int> top(static_cast<std::size_t>(n.x()) * n.y(), -1);
  for (int x = 0; x < n.x(); ++x) {
    for (int y = 0; y < n.y(); ++y) {
      for (int z = 0; z < n.z(); ++z) {
        if (lattice_label(x, y, z) != label::kOutside) top[x * n.y() + y] = z;
      }
    }
  }
  // Pour hole: one voxel column wide, above the highest column top, the column nearest the
  // middle of the body winning ties, and clear of every pin.
  int pour = -1;
  double pour_rank = 0;
  for (int x = 0; x < n.x(); ++x) {
    for (int y = 0; y < n.y(); ++y) {
      const int t = top[x * n.y() + y];
      if (t < 0 || !free_of_pins(column_box(x, y, t, s))) continue;
      const double dx = x + 0.5 - 0.5 * n.x(), dy = y + 0.5 - 0.5 * n.y();
      const double rank = t * 1e6 - (dx * dx + dy * dy);
      if (pour < 0 || rank > pour_rank) {
        pour = x * n.y() + y;
        pour_rank = rank;
      }
    }
  }
  if (pour < 0)
    throw FabricateError(
        "fabricate: --mold: every column of the body is crossed by a pin, so "
        "there is no place for the pour hole");
  mold.pour = column_box(pour / n.y(), pour % n.y(), top[pour], s);
  // Vents: air is trapped under the upper mold at every local top of the body. One vent (as
  // wide as the channels) per plateau of equal column tops that no neighbouring column rises
  // above, at the plateau's first column clear of pins; the pour hole's plateau needs none.
  const double vent_side = fab.options.channel_diameter;
  std::vector<int> plateau(top.size(), -1);
  for (int start = 0; start < static_cast<int>(top.size()); ++start) {
    if (top[start] < 0 || plateau[start] >= 0) continue;
    std::vector<int> members{start}, queue{start};
    plateau[start] = start;
    bool local_top = true;
    while (!queue.empty()) {
      const int c = queue.back();
      queue.pop_back();
      const int x = c / n.y(), y = c % n.y();
      const int nx[4] = {x + 1, x - 1, x, x}, ny[4] = {y, y, y + 1, y - 1};
      for (int k = 0; k < 4; ++k) {
        if (nx[k] < 0 || ny[k] < 0 || nx[k] >= n.x() || ny[k] >= n.y()) continue;
        const int m = nx[k] * n.y() + ny[k];
        if (top[m] > top[start]) local_top = false;
        if (top[m] == top[start] && plateau[m] < 0) {
          plateau[m] = start;
          members.push_back(m);
          queue.push_back(m);
        }
      }
    }
    if (!local_top || plateau[pour] == start) continue;
    std::sort(members.begin(), members.end());
    for (int c : members) {
      const Eigen::AlignedBox3d vent = column_box(c / n.y(), c % n.y(), top[c], vent_side);
      if (free_of_pins(vent)) {
        mold.vents.push_back(vent);
        break;
      }
    }
  }
  // Keys: three square pegs of the lower part (half the wall wide and high) rising into sockets
  // of the upper part at three corners of the wall, so the halves close one way only.
  const double key = 0.5 * w;
  const double lo = -0.5 * w;
  const Eigen::Vector3d hi = n.cast<double>() * s + Eigen::Vector3d::Constant(0.5 * w);
  for (const Eigen::Vector2d& c :
       {Eigen::Vector2d(lo, lo), Eigen::Vector2d(hi.x(), lo), Eigen::Vector2d(lo, hi.y())}) {
    mold.keys.emplace_back(Eigen::Vector3d(c.x() - key / 2, c.y() - key / 2, mold.split_z),
                           Eigen::Vector3d(c.x() + key / 2, c.y() + key / 2, mold.split_z + key));
  }

  std::array<std::vector<double>, 3> planes = fab.grid.planes;
  auto add = [&](const Eigen::AlignedBox3d& b) {
    for (int a = 0; a < 3; ++a) {
      planes[a].push_back(b.min()[a]);
      planes[a].push_back(b.max()[a]);
    }
  };
  add(mold.box);
  for (const auto& b : pins) add(b);
  add(mold.pour);
  for (const auto& b : mold.vents) add(b);
  for (const auto& b : mold.keys) add(b);
  planes[2].push_back(mold.split_z);
  const Grid& body = fab.grid;
  mold.grid = make_grid(planes, [&](const Eigen::Vector3d& p) {
    const int l = body.label_at(p);
    if (l > label::kOutside) return l;  // body, cavity, channel, void
    for (std::size_t q = 0; q < pins.size(); ++q) {
      if (pins[q].contains(p)) return label::kPin + fab.inlets[q].chamber;
    }
    if (mold.pour.contains(p)) return label::kPour;
    for (const auto& v : mold.vents) {
      if (v.contains(p)) return label::kVent;
    }
    for (const auto& k : mold.keys) {
      if (k.contains(p)) return label::kMoldLower;
    }
    return p.z() < mold.split_z ? label::kMoldLower : label::kMoldUpper;
  });

  const std::uint64_t limit = fab.options.max_triangles;
  mold.parts.push_back(extract_mesh(
      mold.grid, [](int l) { return l == label::kMoldLower; }, "mold-lower", limit));
  mold.parts.push_back(extract_mesh(
      mold.grid, [](int l) { return l == label::kMoldUpper; }, "mold-upper", limit));
  for (const Inlet& inlet : fab.inlets) {
    const int q = inlet.chamber;
    mold.cores.push_back(extract_mesh(
        mold.grid,
        [q](int l) {
          return l == label::kCavity + q || l == label::kChannel + q || l == label::kPin + q;
        },
        "core-" + std::to_string(q), limit));
  }
  if (fab.void_cells > 0) {
    mold.cores.push_back(extract_mesh(
        mold.grid, [](int l) { return l == label::kVoid; }, "core-voids", limit));
  }
  return mold;
}

std::string Mold::json() const {
  nlohmann::ordered_json j;
  j["format"] = "softevo.mold/1";
  j["units"] = "mm";
  j["box"] = box_json(box);
  j["split_z_mm"] = mm_rounded(split_z);
  j["pour_hole"] = box_json(pour);
  j["vents"] = nlohmann::ordered_json::array();
  for (const auto& v : vents) j["vents"].push_back(box_json(v));
  j["keys"] = nlohmann::ordered_json::array();
  for (const auto& k : keys) j["keys"].push_back(box_json(k));
  j["files"] = nlohmann::ordered_json::array();
  for (const Mesh& m : parts) {
    j["files"].push_back({{"file", m.name + ".stl"},
                          {"kind", "mold part"},
                          {"volume_mm3", std::round(m.volume() * 1e15) / 1e6}});
  }
  for (const Mesh& m : cores) {
    j["files"].push_back({{"file", m.name + ".stl"},
                          {"kind", "core"},
                          {"volume_mm3", std::round(m.volume() * 1e15) / 1e6}});
  }
  return j.dump(2) + "\n";
}

}  // namespace softevo::fabricate
