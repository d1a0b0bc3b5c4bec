// fabricate/: the meshes of a robot for printing and casting. Every mesh is read back with an
// independent reader (lib3mf's own 3MF reader and its manifold-and-oriented test, and for the
// STLs the binary layout read here by position, never the writer's data) and checked: closed,
// 2-manifold, outward normals, volume = voxels x voxel volume minus the channels; re-voxelized
// at the voxel size, each export gives back the robot's voxels, material groups and chamber
// cavities exactly (the 40 thesis champions and the shipped robots; slices too). The mold's parts
// and cores fill the mold box minus the body exactly. Bad input gets its clear error and leaves
// no file. Random developed bodies always export to valid meshes (property test).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include <Model/COM/NMR_DLLInterfaces.h>

#include "common/rng.hpp"
#include "common/robot.hpp"
#include "evo/development.hpp"
#include "fabricate/fabricate.hpp"
#include "render/png.hpp"
#include "render/render.hpp"
#include "scene/scene.hpp"
#include "tests/random_cppn.hpp"
#include "tests/reference_data.hpp"

namespace softevo::fabricate {
namespace {

namespace fs = std::filesystem;

// A triangle soup as an independent reader sees it: positions [mm], triangles by index.
struct Soup {
  std::string name;
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  double volume_mm3() const {
    double vol = 0;
    for (const auto& f : t) vol += v[f[0]].dot(v[f[1]].cross(v[f[2]]));
    return vol / 6;
  }
};

// lib3mf's reader: every mesh object, its lib3mf manifold test, and the Description.
struct Read3mf {
  std::vector<Soup> objects;
  std::vector<bool> manifold;
  std::string description;
};
Read3mf read_3mf(const std::string& path) {
  Read3mf out;
  NMR::PLib3MFModel* model = nullptr;
  NMR::PLib3MFModelReader* reader = nullptr;
  EXPECT_EQ(NMR::lib3mf_createmodel(&model), LIB3MF_OK);
  EXPECT_EQ(NMR::lib3mf_model_queryreader(model, "3mf", &reader), LIB3MF_OK);
  EXPECT_EQ(NMR::lib3mf_reader_readfromfileutf8(reader, path.c_str()), LIB3MF_OK) << path;
  DWORD count = 0;
  NMR::lib3mf_model_getmetadatacount(model, &count);
  for (DWORD i = 0; i < count; ++i) {
    char key[64] = {}, value[16384] = {};
    ULONG needed = 0;
    NMR::lib3mf_model_getmetadatakeyutf8(model, i, key, sizeof key, &needed);
    NMR::lib3mf_model_getmetadatavalueutf8(model, i, value, sizeof value, &needed);
    if (std::string(key) == "Description") out.description = value;
  }
  NMR::PLib3MFModelResourceIterator* it = nullptr;
  NMR::lib3mf_model_getmeshobjects(model, &it);
  BOOL more = false;
  NMR::lib3mf_resourceiterator_movenext(it, &more);
  while (more) {
    NMR::PLib3MFModelMeshObject* object = nullptr;
    NMR::lib3mf_resourceiterator_getcurrent(it, &object);
    Soup soup;
    char name[128] = {};
    ULONG needed = 0;
    NMR::lib3mf_object_getnameutf8(object, name, sizeof name, &needed);
    soup.name = name;
    DWORD nv = 0, nt = 0;
    NMR::lib3mf_meshobject_getvertexcount(object, &nv);
    NMR::lib3mf_meshobject_gettrianglecount(object, &nt);
    std::vector<NMR::MODELMESHVERTEX> v(nv);
    std::vector<NMR::MODELMESHTRIANGLE> t(nt);
    NMR::lib3mf_meshobject_getvertices(object, v.data(), nv, nullptr);
    NMR::lib3mf_meshobject_gettriangleindices(object, t.data(), nt, nullptr);
    for (const auto& p : v)
      soup.v.emplace_back(p.m_fPosition[0], p.m_fPosition[1], p.m_fPosition[2]);
    for (const auto& f : t) soup.t.push_back({f.m_nIndices[0], f.m_nIndices[1], f.m_nIndices[2]});
    BOOL manifold = false;
    NMR::lib3mf_meshobject_ismanifoldandoriented(object, &manifold);
    out.manifold.push_back(manifold);
    out.objects.push_back(std::move(soup));
    NMR::lib3mf_release(object);
    NMR::lib3mf_resourceiterator_movenext(it, &more);
  }
  NMR::lib3mf_release(it);
  NMR::lib3mf_release(reader);
  NMR::lib3mf_release(model);
  return out;
}

// A binary STL read by its layout (80-byte header, count, 50 bytes per triangle); vertices are
// merged by exact position, as a slicer does.
Soup read_stl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string b = s.str();
  Soup soup;
  soup.name = path;
  EXPECT_GE(b.size(), 84U);
  std::uint32_t n = 0;
  std::memcpy(&n, b.data() + 80, 4);
  EXPECT_EQ(b.size(), 84U + 50ULL * n) << path;
  std::map<std::array<float, 3>, std::uint32_t> index;
  for (std::uint32_t i = 0; i < n; ++i) {
    float f[12];
    std::memcpy(f, b.data() + 84 + 50 * i, sizeof f);
    std::array<std::uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const std::array<float, 3> p{f[3 + 3 * k], f[4 + 3 * k], f[5 + 3 * k]};
      auto [pos, fresh] = index.emplace(p, static_cast<std::uint32_t>(soup.v.size()));
      if (fresh) soup.v.emplace_back(p[0], p[1], p[2]);
      tri[k] = pos->second;
    }
    // The stored normal agrees with the winding (outward when the volume is positive).
    const Eigen::Vector3d a = soup.v[tri[0]], bb = soup.v[tri[1]], c = soup.v[tri[2]];
    EXPECT_GT((bb - a).cross(c - a).normalized().dot(Eigen::Vector3d(f[0], f[1], f[2])), 0.999)
        << path << " triangle " << i << ": " << a.transpose() << " / " << bb.transpose() << " / "
        << c.transpose() << " normal " << f[0] << " " << f[1] << " " << f[2];
    soup.t.push_back(tri);
  }
  return soup;
}

// Closed and oriented: every directed edge has exactly as many reverse uses (by position, so
// also for STL). With `by_index`, also 2-manifold: each directed edge once, and every vertex's
// triangles form a single fan.
void expect_closed(const Soup& s, bool by_index) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& f : s.t) {
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  for (const auto& [e, n] : directed) {
    const auto r = directed.find({e.second, e.first});
    ASSERT_TRUE(r != directed.end() && r->second == n) << s.name << ": open edge";
    if (by_index) {
      ASSERT_EQ(n, 1) << s.name << ": an edge with more than two triangles";
    }
  }
  if (!by_index) return;
  // Vertex fans: around each vertex, next(edge) links the triangles into one cycle.
  std::map<std::uint32_t, std::map<std::uint32_t, std::uint32_t>> fan;  // v -> (a -> b)
  for (const auto& f : s.t) {
    for (int k = 0; k < 3; ++k) fan[f[k]][f[(k + 1) % 3]] = f[(k + 2) % 3];
  }
  for (const auto& [v, next] : fan) {
    std::uint32_t start = next.begin()->first, a = start;
    std::size_t steps = 0;
    do {
      a = next.at(a);
      ++steps;
    } while (a != start && steps <= next.size());
    ASSERT_EQ(steps, next.size()) << s.name << ": vertex " << v << " is not one fan";
  }
}

// Inside test by ray parity along +z: the horizontal triangles above a point, bucketed by the
// lattice column their footprint covers.
class Inside {
 public:
  Inside(const Soup& s, double cell_mm) : soup_(s), cell_(cell_mm) {
    for (std::size_t i = 0; i < s.t.size(); ++i) {
      const auto& f = s.t[i];
      const Eigen::Vector3d n = (s.v[f[1]] - s.v[f[0]]).cross(s.v[f[2]] - s.v[f[0]]);
      if (std::abs(n.z()) < 1e-12) continue;
      Eigen::Vector3d lo = s.v[f[0]].cwiseMin(s.v[f[1]]).cwiseMin(s.v[f[2]]);
      Eigen::Vector3d hi = s.v[f[0]].cwiseMax(s.v[f[1]]).cwiseMax(s.v[f[2]]);
      for (int x = key(lo.x()); x <= key(hi.x()); ++x)
        for (int y = key(lo.y()); y <= key(hi.y()); ++y) buckets_[{x, y}].push_back(i);
    }
  }
  bool operator()(const Eigen::Vector3d& p) const {
    const auto b = buckets_.find({key(p.x()), key(p.y())});
    if (b == buckets_.end()) return false;
    int crossings = 0;
    for (std::size_t i : b->second) {
      const auto& f = soup_.t[i];
      const Eigen::Vector3d &a = soup_.v[f[0]], &bb = soup_.v[f[1]], &c = soup_.v[f[2]];
      auto side = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& w) {
        return (w.x() - u.x()) * (p.y() - u.y()) - (w.y() - u.y()) * (p.x() - u.x());
      };
      const double s1 = side(a, bb), s2 = side(bb, c), s3 = side(c, a);
      const bool in = (s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0);
      if (in && a.z() > p.z()) ++crossings;  // horizontal: all three at one z
    }
    return crossings % 2 == 1;
  }

 private:
  int key(double mm) const { return static_cast<int>(std::floor(mm / cell_)); }
  const Soup& soup_;
  double cell_;
  std::map<std::pair<int, int>, std::vector<std::size_t>> buckets_;
};

// Sample points of a lattice cell [mm]: a 3 x 3 x 3 pattern at odd fractions, off every channel
// axis and every quad diagonal.
std::vector<Eigen::Vector3d> samples(const Eigen::Vector3i& c, double s_mm) {
  std::vector<Eigen::Vector3d> out;
  const double fx[3] = {0.1123, 0.3871, 0.8317}, fy[3] = {0.1379, 0.6913, 0.8741},
               fz[3] = {0.1931, 0.3119, 0.7777};
  for (double x : fx)
    for (double y : fy)
      for (double z : fz)
        out.emplace_back((c.x() + x) * s_mm, (c.y() + y) * s_mm, (c.z() + z) * s_mm);
  return out;
}

// Cells marked -1 that are 6-connected to the lattice border become air (0).
void flood_air(std::vector<int>& cells, const std::array<int, 3>& d) {
  auto index = [&](const std::array<int, 3>& c) {
    return (static_cast<std::size_t>(c[0]) * d[1] + c[1]) * d[2] + c[2];
  };
  std::vector<std::array<int, 3>> stack;
  for (int x = 0; x < d[0]; ++x)
    for (int y = 0; y < d[1]; ++y)
      for (int z = 0; z < d[2]; ++z)
        if (x == 0 || y == 0 || z == 0 || x == d[0] - 1 || y == d[1] - 1 || z == d[2] - 1)
          stack.push_back({x, y, z});
  for (const auto& c : stack) cells[index(c)] = cells[index(c)] == -1 ? -2 : cells[index(c)];
  std::erase_if(stack, [&](const auto& c) { return cells[index(c)] != -2; });
  while (!stack.empty()) {
    const auto c = stack.back();
    stack.pop_back();
    cells[index(c)] = 0;
    for (int a = 0; a < 3; ++a)
      for (int s : {-1, 1}) {
        auto m = c;
        m[a] += s;
        if (m[a] < 0 || m[a] >= d[a] || cells[index(m)] != -1) continue;
        cells[index(m)] = -2;
        stack.push_back(m);
      }
  }
}

// The robot's cells as the export should give them back: material k, or 100 + q for a chamber
// cell, 250 for an enclosed empty cell, 0 for air.
std::vector<int> expected_cells(const BodyPlan& plan) {
  std::vector<int> out(plan.cells.size(), -1);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int v = plan.cells[i];
    if (BodyPlan::is_structural(v)) out[i] = v;
    if (BodyPlan::is_chamber(v)) out[i] = 100 + v - kFirstChamberCell;
  }
  flood_air(out, plan.lattice);
  for (int& o : out) o = o == -1 ? 250 : o;
  return out;
}

struct Exported {
  std::vector<Soup> groups;  // by material
  std::vector<int> materials;
};

// Re-voxelizes group meshes: a cell is material k when most of its samples are inside group
// k's mesh; the cells inside none are then air when 6-connected to the lattice border, else
// enclosed (a chamber's cavity or a void).
std::vector<int> revoxelize(const Exported& e, const std::array<int, 3>& d, double s_mm) {
  std::vector<Inside> inside;
  for (const Soup& g : e.groups) inside.emplace_back(g, s_mm);
  std::vector<int> out(static_cast<std::size_t>(d[0]) * d[1] * d[2], -1);
  auto at = [&](int x, int y, int z) -> int& {
    return out[(static_cast<std::size_t>(x) * d[1] + y) * d[2] + z];
  };
  for (int x = 0; x < d[0]; ++x)
    for (int y = 0; y < d[1]; ++y)
      for (int z = 0; z < d[2]; ++z)
        for (std::size_t g = 0; g < inside.size(); ++g) {
          int hits = 0;
          const auto pts = samples({x, y, z}, s_mm);
          for (const auto& p : pts) hits += inside[g](p);
          if (2 * hits > static_cast<int>(pts.size())) at(x, y, z) = e.materials[g];
        }
  flood_air(out, d);
  return out;
}

// Enclosed cells of `cells` (chambers 100 + q and voids 250) as one code: the meshes carry no
// chamber index, only that the cell is an enclosed cavity (checked per chamber by the inlets).
std::vector<int> merge_enclosed(std::vector<int> cells) {
  for (int& c : cells) c = c >= 100 || c == -1 ? 1000 : c;
  return cells;
}

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("softevo_test_fabricate_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

Provenance provenance_of(const RobotFile& robot) {
  Provenance pv;
  pv.name = robot.name;
  for (const auto& m : robot.body.materials) pv.youngs_modulus.push_back(m.youngs_modulus);
  return pv;
}

// Slices of 2.5 mm pixels (4 per voxel) and one layer per voxel: the pixel 1 of each cell
// (3.75 mm in, off every channel's axis) holds the cell's material, or 100 + q for chamber q's
// cavity: the slices give back even the chamber index.
void check_slices(const RobotFile& robot, const fs::path& dir) {
  const scene::Body body = scene::body_from_plan(robot.body);
  Options o;
  o.dpi_x = o.dpi_y = 0.0254 / 2.5e-3;
  o.layer = body.voxel_size;
  const Fabrication fab = fabricate(body, provenance_of(robot), o);
  const int layers = write_slices(fab, dir.string(), Overwrite::replace);
  EXPECT_EQ(layers, fab.lattice.z());
  const std::vector<int> want = expected_cells(robot.body);
  const auto& d = robot.body.lattice;
  for (int z = 0; z < d[2]; ++z) {
    char name[32];
    std::snprintf(name, sizeof name, "slice-%05d.png", z);
    const render::Image im = render::read_png((dir / name).string());
    ASSERT_EQ(im.width, d[0] * 4);
    ASSERT_EQ(im.height, d[1] * 4);
    for (int x = 0; x < d[0]; ++x)
      for (int y = 0; y < d[1]; ++y)
        ASSERT_EQ(im.pixel(x * 4 + 1, y * 4 + 1)[0], want[robot.body.cell_index(x, y, z)])
            << "slice " << name << " cell " << x << " " << y;
  }
  EXPECT_TRUE(fs::exists(dir / "palette.json"));
}

// The whole check of one robot: 3MF (lib3mf) and STL, volumes, manifoldness, round trip.
void check_robot(const RobotFile& robot, const fs::path& dir, bool with_mold) {
  SCOPED_TRACE(robot.name);
  const scene::Body body = scene::body_from_plan(robot.body);
  const Fabrication fab = fabricate(body, provenance_of(robot), {});
  const double s_mm = fab.voxel_size * 1e3, d_mm = fab.options.channel_diameter * 1e3;
  const std::string out3 = (dir / "robot.3mf").string();
  write_3mf(fab, out3, Overwrite::replace);
  const Read3mf r = read_3mf(out3);
  ASSERT_EQ(r.objects.size(), fab.groups.size());
  // Channel volume from the Description's inlet lines (what the file says, not the writer).
  double channels_mm3 = 0;
  const std::regex inlet(R"(through (\d+) wall voxels)");
  int inlets = 0;
  for (std::sregex_iterator m(r.description.begin(), r.description.end(), inlet), end; m != end;
       ++m, ++inlets)
    channels_mm3 += std::stoi((*m)[1]) * s_mm * d_mm * d_mm;
  EXPECT_EQ(inlets, robot.body.chamber_count());
  double total = 0;
  std::size_t voxels = 0;
  Exported e3, es;
  for (std::size_t g = 0; g < r.objects.size(); ++g) {
    EXPECT_TRUE(r.manifold[g]) << r.objects[g].name;
    expect_closed(r.objects[g], true);
    EXPECT_GT(r.objects[g].volume_mm3(), 0);
    total += r.objects[g].volume_mm3();
    voxels += fab.groups[g].voxels;
    e3.groups.push_back(r.objects[g]);
    e3.materials.push_back(fab.groups[g].material);
  }
  const double expected = voxels * s_mm * s_mm * s_mm - channels_mm3;
  EXPECT_NEAR(total, expected, 1e-6 * expected);
  // STL: the same volumes, closed by position, normals outward.
  for (const std::string& path :
       write_stls(fab, (dir / "robot.stl").string(), Overwrite::replace)) {
    es.groups.push_back(read_stl(path));
    expect_closed(es.groups.back(), false);
  }
  es.materials = e3.materials;
  double stl_total = 0;
  for (const Soup& sp : es.groups) stl_total += sp.volume_mm3();
  EXPECT_NEAR(stl_total, expected, 1e-6 * expected);
  // Round trip at the voxel size.
  const std::array<int, 3> d{fab.lattice.x(), fab.lattice.y(), fab.lattice.z()};
  std::vector<int> want = expected_cells(robot.body);
  want.resize(static_cast<std::size_t>(d[0]) * d[1] * d[2]);  // a plan trimmed to the body
  EXPECT_EQ(merge_enclosed(revoxelize(e3, d, s_mm)), merge_enclosed(want)) << "3MF";
  EXPECT_EQ(merge_enclosed(revoxelize(es, d, s_mm)), merge_enclosed(want)) << "STL";
  check_slices(robot, dir / "slices");
  // Each chamber's inlet opens its own cavity: the mouth lies on the body's outer face, and
  // a point just inside the cavity behind it is enclosed in no group.
  for (const Inlet& in : fab.inlets) {
    EXPECT_EQ(
        want[(static_cast<std::size_t>(in.cell.x()) * d[1] + in.cell.y()) * d[2] + in.cell.z()],
        100 + in.chamber);
  }
  if (!with_mold) return;
  // Mold: the parts, the cores and the body fill the box exactly: read every STL back, sample
  // the centre of every cell of the grid their vertices span, and find each centre in exactly
  // one piece (or the pour hole and vents, which are empty by design).
  const Mold mold = make_mold(fab);
  const auto files = write_mold(mold, (dir / "mold").string(), Overwrite::replace);
  std::vector<Soup> pieces;
  std::array<std::set<double>, 3> planes;
  for (const auto& f : files) {
    if (f.size() < 4 || f.substr(f.size() - 4) != ".stl") continue;
    pieces.push_back(read_stl(f));
    expect_closed(pieces.back(), false);
    EXPECT_GT(pieces.back().volume_mm3(), 0) << f;
  }
  for (const Soup& g : es.groups) pieces.push_back(g);
  for (const Soup& sp : pieces)
    for (const auto& v : sp.v)
      for (int a = 0; a < 3; ++a) planes[a].insert(v[a]);
  std::vector<Inside> inside;
  for (const Soup& sp : pieces) inside.emplace_back(sp, s_mm);
  const std::vector<double> px(planes[0].begin(), planes[0].end()),
      py(planes[1].begin(), planes[1].end()), pz(planes[2].begin(), planes[2].end());
  double empty_mm3 = 0,
         box_mm3 = (px.back() - px.front()) * (py.back() - py.front()) * (pz.back() - pz.front());
  for (std::size_t i = 0; i + 1 < px.size(); ++i)
    for (std::size_t j = 0; j + 1 < py.size(); ++j)
      for (std::size_t k = 0; k + 1 < pz.size(); ++k) {
        const Eigen::Vector3d c(0.5 * (px[i] + px[i + 1]) + 1e-7, 0.5 * (py[j] + py[j + 1]) + 3e-7,
                                0.5 * (pz[k] + pz[k + 1]));
        int owners = 0;
        for (const Inside& in : inside) owners += in(c);
        const double vol = (px[i + 1] - px[i]) * (py[j + 1] - py[j]) * (pz[k + 1] - pz[k]);
        if (owners == 0) {
          // Empty: only in the pour hole or a vent.
          bool hole = mold.pour.contains(c * 1e-3);
          for (const auto& v : mold.vents) hole = hole || v.contains(c * 1e-3);
          ASSERT_TRUE(hole) << "gap at " << c.transpose() << " mm";
          empty_mm3 += vol;
        } else {
          ASSERT_EQ(owners, 1) << "overlap at " << c.transpose() << " mm";
        }
      }
  double pieces_mm3 = 0;
  for (const Soup& sp : pieces) pieces_mm3 += sp.volume_mm3();
  EXPECT_NEAR(pieces_mm3 + empty_mm3, box_mm3, 1e-6 * box_mm3);
}

TEST(ExtractMesh, OneCellIsACubeOfTwelveTriangles) {
  const Grid g = make_grid({std::vector<double>{0, 1}, {0, 1}, {0, 1}},
                           [](const Eigen::Vector3d&) { return 1; });
  const Mesh m = extract_mesh(
      g, [](int l) { return l == 1; }, "cube", 100);
  EXPECT_EQ(m.triangles.size(), 12U);
  EXPECT_EQ(m.vertices.size(), 8U);
  EXPECT_DOUBLE_EQ(m.volume(), 1.0);
}

TEST(ExtractMesh, CellsTouchingAlongAnEdgeOrAtACornerStayManifold) {
  // Two cells meeting along an edge, two meeting at a corner, and the worst case: an edge whose
  // two sheets join at both its ends (a 2 x 2 x 2 block with two opposite cells of one layer
  // missing and the layer below full).
  const std::vector<std::vector<Eigen::Vector3i>> shapes = {
      {{0, 0, 0}, {1, 1, 0}},
      {{0, 0, 0}, {1, 1, 1}},
      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 1, 1}},
  };
  for (const auto& cells : shapes) {
    const Grid g = make_grid({std::vector<double>{0, 1, 2}, {0, 1, 2}, {0, 1, 2}},
                             [&](const Eigen::Vector3d& p) {
                               const Eigen::Vector3i c = p.cast<int>();
                               return std::count(cells.begin(), cells.end(), c) > 0 ? 1 : 0;
                             });
    const Mesh m = extract_mesh(
        g, [](int l) { return l == 1; }, "shape", 1000);
    Soup s{"shape", m.vertices, m.triangles};
    expect_closed(s, true);
    EXPECT_NEAR(m.volume(), static_cast<double>(cells.size()), 1e-12);
  }
}

TEST(ExtractMesh, MoreTrianglesThanTheLimitIsAnError) {
  const Grid g = make_grid({std::vector<double>{0, 1}, {0, 1}, {0, 1}},
                           [](const Eigen::Vector3d&) { return 1; });
  EXPECT_THROW(extract_mesh(
                   g, [](int l) { return l == 1; }, "cube", 11),
               FabricateError);
}

std::vector<fs::path> shipped_and_champions() {
  std::vector<fs::path> out;
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  const fs::path root = env ? fs::path(env) : fs::current_path();
  for (const auto& e : fs::directory_iterator(root / "robots"))
    if (e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Fabricate, ShippedRobotsRoundTripThroughEveryFormatAndSlicesAndTheirMoldsFillTheBox) {
  const fs::path dir = temp_dir("shipped");
  for (const fs::path& p : shipped_and_champions())
    check_robot(read_robot_file(p.string()), dir, true);
  fs::remove_all(dir);
}

TEST(Fabricate, TheFortyThesisChampionsRoundTripThroughEveryFormatAndSlices) {
  const fs::path bots = test::reference_bestbots();
  if (!fs::is_directory(bots)) GTEST_SKIP() << bots << " is absent";
  const fs::path dir = temp_dir("champions");
  int n = 0;
  for (const auto& e : fs::directory_iterator(bots)) {
    if (e.path().extension() != ".json") continue;
    // Every fifth champion also with its mold (all 40 pass; the mold check is the slow part).
    check_robot(read_robot_file(e.path().string()), dir, n++ % 5 == 0);
  }
  EXPECT_EQ(n, 40);
  fs::remove_all(dir);
}

TEST(Fabricate, GroupsOfOneModulusGetDistinctNames) {
  const fs::path p = shipped_and_champions().front();  // dir-open-steerable: 5 groups
  const RobotFile robot = read_robot_file(p.string());
  Provenance pv = provenance_of(robot);
  pv.youngs_modulus.assign(10, 5.0e4);
  const Fabrication fab = fabricate(scene::body_from_plan(robot.body), pv, {});
  std::set<std::string> names;
  for (const auto& g : fab.groups) names.insert(g.name);
  EXPECT_GT(fab.groups.size(), 2U);
  EXPECT_EQ(names.size(), fab.groups.size());
  EXPECT_EQ(fab.groups.front().name, "E50000Pa");
}

TEST(Fabricate, CutawayKeepsTheCellsBehindTheSectionAndTheirChannelPieces) {
  for (const fs::path& p : shipped_and_champions()) {
    SCOPED_TRACE(p.string());
    const scene::Body body = scene::body_from_plan(read_robot_file(p.string()).body);
    const std::vector<scene::Pose> poses{scene::rest_pose(body)};
    const Cutaway cut = cut_away(body, poses, std::nullopt);
    // The default section keeps every channel whole.
    const Fabrication whole = fabricate(body, {}, {});
    EXPECT_EQ(cut.channels.size(), channel_pieces(whole, body).size());
    std::size_t behind = 0;
    for (const auto& c : body.voxel_cells) behind += c.y() >= cut.cut_y;
    EXPECT_EQ(cut.body.voxel_cells.size(), behind);
    for (const auto& c : cut.body.voxel_cells) EXPECT_GE(c.y(), cut.cut_y);
    for (const auto& c : cut.body.chamber_cells) EXPECT_GE(c.y(), cut.cut_y);
    ASSERT_EQ(cut.poses.size(), 1U);
    ASSERT_EQ(cut.poses[0].position.size(), behind);
    for (std::size_t i = 0; i < behind; ++i)
      EXPECT_EQ(cut.poses[0].position[i], cut.body.voxel_cells[i].cast<double>() * body.voxel_size);
    // Every channel piece left is in a kept voxel; all of them when nothing of theirs was cut.
    const Fabrication fab = fabricate(body, {}, {});
    std::size_t expected = 0;
    for (const ChannelPiece& piece : channel_pieces(fab, body))
      expected += body.voxel_cells[piece.voxel].y() >= cut.cut_y;
    EXPECT_EQ(cut.channels.size(), expected);
    for (const ChannelPiece& piece : cut.channels)
      EXPECT_LT(piece.voxel, static_cast<int>(cut.body.voxel_cells.size()));
    EXPECT_THROW(cut_away(body, poses, 1000), FabricateError);
  }
}

// Bad input: each gets its clear error, naming the option, and no file is left.
TEST(Fabricate, BadInputIsAClearErrorAndWritesNothing) {
  const RobotFile robot = read_robot_file(shipped_and_champions().front().string());
  const scene::Body body = scene::body_from_plan(robot.body);
  auto error_of = [&](const scene::Body& b, const Options& o, bool mold = false) -> std::string {
    try {
      const Fabrication fab = fabricate(b, provenance_of(robot), o);
      if (mold) make_mold(fab);
    } catch (const FabricateError& e) {
      return e.what();
    }
    return "";
  };
  scene::Body empty = body;
  empty.voxel_cells.clear();
  empty.voxel_material.clear();
  EXPECT_NE(error_of(empty, {}).find("no voxels"), std::string::npos);
  Options wide;
  wide.channel_diameter = body.voxel_size;
  EXPECT_NE(error_of(body, wide).find("--channel-diameter"), std::string::npos);
  Options split;
  split.split_z = -0.001;
  EXPECT_NE(error_of(body, split, true).find("--split"), std::string::npos);
  split.split_z = 10.0;
  EXPECT_NE(error_of(body, split, true).find("--split"), std::string::npos);
  Options triangles;
  triangles.max_triangles = 100;
  EXPECT_NE(error_of(body, triangles).find("triangles"), std::string::npos);
  // A chamber walled in by another chamber on every side it could leave by.
  scene::Body boxed;
  boxed.voxel_size = 0.01;
  for (int x = 0; x < 7; ++x)
    for (int y = 0; y < 7; ++y)
      for (int z = 0; z < 7; ++z) {
        const int r = std::max({std::abs(x - 3), std::abs(y - 3), std::abs(z - 3)});
        if (r == 0) {
          boxed.chamber_cells.emplace_back(x, y, z);
          boxed.chamber_index.push_back(0);
        } else if (r == 2) {
          boxed.chamber_cells.emplace_back(x, y, z);
          boxed.chamber_index.push_back(1);
        } else {
          boxed.voxel_cells.emplace_back(x, y, z);
          boxed.voxel_material.push_back(5);
        }
      }
  boxed.chamber_count = 2;
  EXPECT_NE(error_of(boxed, {}).find("chamber 0 has no straight path"), std::string::npos);
  // Slices beyond the pixel limit: refused before the directory is made.
  const fs::path dir = temp_dir("bad") / "slices";
  Options pixels;
  pixels.max_pixels = 1000;
  const Fabrication fab = fabricate(body, provenance_of(robot), pixels);
  try {
    write_slices(fab, dir.string(), Overwrite::refuse);
    ADD_FAILURE() << "no error";
  } catch (const FabricateError& e) {
    // The figures as given and as counted, in their shortest form (no "600.000000").
    EXPECT_NE(std::string(e.what()).find("--dpi 600,300 and --layer-um 30 would be "),
              std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).find(".000000"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir));
  // A --slices or --mold directory that cannot be made (its parent is not there, even for
  // root) is found before the 3MF is written: no output is left behind.
  for (const bool mold : {false, true}) {
    Request request;
    request.output = (dir.parent_path() / "kept-out.3mf").string();
    (mold ? request.mold : request.slices) = "/proc/softevo-no-such-directory/out";
    try {
      fabricate_robot(robot, provenance_of(robot), request);
      ADD_FAILURE() << "no error";
    } catch (const FabricateError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(mold ? "--mold" : "--slices") +
                                           " /proc/softevo-no-such-directory/out: cannot create "
                                           "the directory"),
                std::string::npos)
          << e.what();
    }
    EXPECT_FALSE(fs::exists(request.output)) << request.output;
  }
  fs::remove_all(dir.parent_path());
}

// `--check` of something that is not a 3MF file says what it is, and a FIFO never blocks the
// reader (before, lib3mf opened it and waited for a writer forever).
TEST(Fabricate, CheckOfAFileThatIsNotA3mfSaysWhatItIs) {
  const fs::path dir = temp_dir("check");
  const auto error_of = [](const fs::path& path) -> std::string {
    try {
      check_3mf(path.string());
    } catch (const FabricateError& e) {
      return e.what();
    }
    return "";
  };
  const fs::path fifo = dir / "pipe.3mf";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  EXPECT_NE(error_of(fifo).find("pipe.3mf: is a FIFO (named pipe), not a 3MF file"),
            std::string::npos)
      << error_of(fifo);
  EXPECT_NE(error_of(dir).find("is a directory, not a 3MF file"), std::string::npos);
  EXPECT_NE(error_of(dir / "missing.3mf").find("missing.3mf: no such file"), std::string::npos);
  const fs::path robot = shipped_and_champions().front();
  EXPECT_NE(error_of(robot).find("not a 3MF file (a 3MF file is a ZIP package); this is JSON: a "
                                 "robot file?"),
            std::string::npos)
      << error_of(robot);
  // A ZIP package that lib3mf cannot read is still lib3mf's error, naming the file.
  const fs::path cut = dir / "cut.3mf";
  std::ofstream(cut, std::ios::binary) << std::string("PK\x03\x04", 4) << std::string(60, '\0');
  EXPECT_NE(error_of(cut).find("fabricate --check " + cut.string() + ": lib3mf: "),
            std::string::npos)
      << error_of(cut);
  fs::remove_all(dir);
}

// Property: random CPPNs develop random bodies; each exports to closed, manifold meshes whose
// volumes add up, or gets one of the clear errors (a chamber with no straight path).
TEST(Fabricate, RandomDevelopedBodiesExportToValidMeshes) {
  Rng rng(2042);
  BodyConfig config;
  config.lattice = {10, 10, 10};
  int exported = 0, refused = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const evo::DevelopedBody developed = evo::develop_body(test::random_cppn(rng), config);
    if (!developed.valid) continue;
    const scene::Body body = scene::body_from_plan(developed.plan);
    Provenance pv;
    try {
      const Fabrication fab = fabricate(body, pv, {});
      double volume = 0;
      for (const auto& g : fab.groups) {
        expect_closed(Soup{g.name, g.mesh.vertices, g.mesh.triangles}, true);
        volume += g.mesh.volume();
      }
      const double s3 = std::pow(fab.voxel_size, 3);
      EXPECT_NEAR(volume, body.voxel_cells.size() * s3 - fab.channel_volume, 1e-9 * volume);
      const Mold mold = make_mold(fab);
      for (const auto& m : mold.parts) expect_closed(Soup{m.name, m.vertices, m.triangles}, true);
      for (const auto& m : mold.cores) expect_closed(Soup{m.name, m.vertices, m.triangles}, true);
      ++exported;
    } catch (const FabricateError& e) {
      EXPECT_NE(std::string(e.what()).find("has no straight path"), std::string::npos) << e.what();
      ++refused;
    }
  }
  std::printf("%d random bodies exported with their molds, %d refused (no straight inlet)\n",
              exported, refused);
  EXPECT_GT(exported, 10) << refused << " refused";
}

}  // namespace
}  // namespace softevo::fabricate
