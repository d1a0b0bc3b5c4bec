// From simulation to the workshop: an evolved robot as printable and castable geometry
// (docs/fabrication.md). Everything is computed on a rectilinear grid whose planes are the voxel
// lattice's plus those of the inlet channels and, for a mold, of the mold box, the split plane,
// the vents and the keys. Each grid cell has one label (a material group, a chamber's cavity, a
// channel, a mold part, ...), and a mesh is the boundary between the cells of one label set and
// the rest: closed and oriented by construction, with exact coordinates and volume, and no mesh
// booleans. Where two cells of a set meet only along an edge or at a corner, the surface is kept
// 2-manifold by giving each side its own vertices (extract_mesh).
//
// The room: on scene::Body (motion::load_motion or scene::body_from_plan make one) and common;
// render/ only for the stiffness colours and PNG writing. Never physics, evo, io or MPI
// (tests/common/test_module_rules.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/robot.hpp"
#include "common/safe_write.hpp"
#include "scene/scene.hpp"

namespace softevo::fabricate {

// Bad input or an option out of range: the message names the option (or the chamber by index)
// and the reason. Nothing has been written when it is thrown.
class FabricateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The options of `softevo fabricate` and Robot.fabricate (SI units inside; the CLI takes mm).
struct Options {
  double scale = 1.0;                   // --scale: printed voxel edge = voxel_size x scale
  double channel_diameter = 1.5e-3;     // [m] --channel-diameter: side of the square inlet channel
  double wall = 3.0e-3;                 // [m] --wall: mold material around the body
  std::optional<double> split_z;        // [m] --split z=: mold split height above the body's bottom
  double dpi_x = 600.0, dpi_y = 300.0;  // [1/inch] --dpi X,Y of the slices
  double layer = 30.0e-6;               // [m] --layer-um: slice thickness
  // Stated limits (docs/fabrication.md): a --scale, --dpi or --layer-um that would exceed them is
  // refused before anything is computed or written.
  std::uint64_t max_triangles = 20'000'000;   // per export (all meshes together)
  std::uint64_t max_pixels = 20'000'000'000;  // slices: width x height x layers
  // false: the grid and the inlets only, no meshes (what the viewer and render --cutaway need).
  bool meshes = true;
};

// What the 3MF metadata records about the robot (all optional but the materials).
struct Provenance {
  std::string name;
  std::optional<std::int64_t> genome_id;
  std::optional<std::int64_t> generation;
  std::string run;
  std::string config_hash;
  std::optional<double> fitness;
  std::vector<double> youngs_modulus;  // [Pa] of material k at [k-1]; empty: 10 kPa x k (§10)
};

// Labels of the cells of a fabrication grid.
namespace label {
inline constexpr int kOutside = 0;    // air around the body
inline constexpr int kCavity = 100;   // + q: chamber q's gas region (its chamber cells, §3.1)
inline constexpr int kChannel = 200;  // + q: chamber q's inlet channel through its wall
inline constexpr int kVoid = 250;     // enclosed empty cell that is no chamber (no inlet)
inline constexpr int kMoldLower = 300;
inline constexpr int kMoldUpper = 301;
inline constexpr int kPin = 400;   // + q: the inlet pin of chamber q's core, through the mold wall
inline constexpr int kPour = 500;  // the pour hole (empty)
inline constexpr int kVent = 501;  // a vent (empty)
inline bool is_material(int l) {
  return l >= 1 && l < kCavity;
}
}  // namespace label

// A rectilinear grid: cell (i, j, k) spans [planes[0][i], planes[0][i+1]] x ... and has one label.
struct Grid {
  std::array<std::vector<double>, 3> planes;  // [m] ascending, one more than cells per axis
  std::vector<std::int16_t> labels;           // index (i * ny + j) * nz + k

  Eigen::Vector3i cells() const;
  int at(int i, int j, int k) const;
  // The cell holding `point` [m] on each axis (-1 outside the grid).
  int axis_cell(int axis, double coordinate) const;
  // The label at `point` [m], -1 outside the grid.
  int label_at(const Eigen::Vector3d& point) const;
  double cell_volume(int i, int j, int k) const;  // [m^3]
};

// Sorts and de-duplicates the planes, then labels every cell by its centre [m].
Grid make_grid(std::array<std::vector<double>, 3> planes,
               const std::function<int(const Eigen::Vector3d& centre)>& label_of);

// An indexed triangle mesh, counter-clockwise seen from outside (outward normals).
struct Mesh {
  std::string name;
  std::vector<Eigen::Vector3d> vertices;                // [m]
  std::vector<std::array<std::uint32_t, 3>> triangles;  // vertex indices
  double volume() const;                                // [m^3], divergence theorem
};

// The boundary of the cells whose label satisfies `inside`: one quad (two triangles) per cell
// face between an inside and an outside cell (the grid's border counts as outside). Vertices are
// shared along every edge and corner where the surface is locally a disc; where two inside
// cells touch only along an edge or at a corner, each keeps its own vertex there, so every edge
// has exactly two triangles and every vertex one fan: a closed, oriented 2-manifold.
// Throws FabricateError when more than `max_triangles` triangles would be made.
Mesh extract_mesh(const Grid& grid, const std::function<bool(int label)>& inside,
                  const std::string& name, std::uint64_t max_triangles);

// Chamber q's inlet: a straight channel of square section from one of its cells through the wall
// to the outside, along a lattice axis (docs/fabrication.md "Channels").
struct Inlet {
  int chamber = 0;
  Eigen::Vector3i cell;     // the chamber cell it starts from
  int face = 0;             // direction: scene::kFaceSteps[face]
  int wall_cells = 0;       // wall voxels it passes through
  Eigen::AlignedBox3d box;  // [m] the channel, from the cavity to the outer face
  Eigen::Vector3d mouth;    // [m] centre of its opening on the outer face
};

struct MaterialGroup {
  int material = 0;                      // 1..10
  double youngs_modulus = 0;             // [Pa]
  std::array<std::uint8_t, 3> colour{};  // as softevo render colours it
  std::size_t voxels = 0;
  Mesh mesh;
  // "E<modulus>Pa" (E30000Pa); "E<modulus>Pa-m<material>" when two groups share a modulus.
  std::string name;
};

// The body as printable geometry.
struct Fabrication {
  double voxel_size = 0;    // [m] printed edge (voxel_size x scale)
  Eigen::Vector3i lattice;  // cells along x, y, z
  // Per lattice cell (index (x * Y + y) * Z + z): label::kOutside, material 1..10,
  // kCavity + q or kVoid.
  std::vector<int> lattice_labels;
  Grid grid;                  // the lattice refined by the channel planes, channels labelled
  std::vector<Inlet> inlets;  // one per chamber, in chamber order
  std::vector<MaterialGroup> groups;  // ascending material, only those present
  std::size_t voxel_count = 0, cavity_cells = 0, void_cells = 0;
  double channel_volume = 0;  // [m^3] all channels
  Provenance provenance;
  Options options;
  std::string summary() const;
};

// Throws FabricateError for a body with no voxels, a chamber with no straight path through its
// wall to the outside (named by index), a channel not narrower than the wall (one voxel), an
// option out of range or more triangles than the limit.
Fabrication fabricate(const scene::Body& body, const Provenance& provenance,
                      const Options& options);

// An inlet channel cut into voxel-sized pieces, each in the frame of the wall voxel it passes
// through, for drawing it with a moving body (softevo view's fabrication box, render
// --cutaway): the box's centre relative to the voxel's centre and its size [m].
struct ChannelPiece {
  int chamber = 0;
  int voxel = 0;  // index into body.voxel_cells
  Eigen::Vector3d centre, size;
};
std::vector<ChannelPiece> channel_pieces(const Fabrication& fabrication, const scene::Body& body);

// `softevo render --cutaway`: the body and its poses without the cells in front of the section
// plane (cells with y < cut_y, the side view's camera being on the -y side), and the channel
// pieces that remain, re-indexed to the cut body. Default cut_y: every channel kept whole, and
// among the rows that allow it, the one holding the most chamber cells (the deepest on ties), so
// the section opens chambers and every inlet shows. Throws
// FabricateError when the cut leaves no voxel or `cut_y` is outside the lattice.
struct Cutaway {
  scene::Body body;
  std::vector<scene::Pose> poses;
  std::vector<ChannelPiece> channels;
  int cut_y = 0;
};
Cutaway cut_away(const scene::Body& body, const std::vector<scene::Pose>& poses,
                 std::optional<int> cut_y);

// The two-part casting mold and the cores (docs/fabrication.md "Mold").
struct Mold {
  Grid grid;                 // the mold box, every cell one of: body material, cavity,
                             // channel, void, lower, upper, pin, pour, vent
  Eigen::AlignedBox3d box;   // [m]
  double split_z = 0;        // [m]
  Eigen::AlignedBox3d pour;  // [m] the pour hole
  std::vector<Eigen::AlignedBox3d> vents, keys;  // [m]
  std::vector<Mesh> parts;                       // lower, upper
  std::vector<Mesh> cores;   // chamber q's cavity with its channel and pin; then the voids, if any
  std::string json() const;  // mold.json: what each file is, the box, split, pour, vents, keys
};
Mold make_mold(const Fabrication& fabrication);

// Files: every check and every mesh is done before the first byte is written; each file is
// written atomically (common/safe_write.hpp).
void write_3mf(const Fabrication& fabrication, const std::string& path, Overwrite overwrite);
// OUT-<group>.stl for each group (binary STL, mm); returns the paths.
std::vector<std::string> write_stls(const Fabrication& fabrication, const std::string& out,
                                    Overwrite overwrite);
// DIR/slice-00000.png ... and DIR/palette.json; returns the number of slices.
int write_slices(const Fabrication& fabrication, const std::string& dir, Overwrite overwrite);
// DIR/mold-lower.stl, mold-upper.stl, core-<q>.stl, core-voids.stl, mold.json; returns the paths.
std::vector<std::string> write_mold(const Mold& mold, const std::string& dir, Overwrite overwrite);
std::string stl_bytes(const Mesh& mesh);  // binary STL in mm
// The paths those writers write, for checking every target before the first is written.
std::vector<std::string> stl_paths(const Fabrication& fabrication, const std::string& out);
std::vector<std::string> slice_paths(const Fabrication& fabrication, const std::string& dir);
std::vector<std::string> mold_paths(const Mold& mold, const std::string& dir);
// The directory `dir` of `option` (--slices, --mold), created with its parents if missing;
// FabricateError naming both when it cannot be. Made before the first file is written, so that
// a directory that cannot be made leaves no other output behind.
void make_output_directory(const std::string& dir, const char* option);
// Slice images: pixels [count] and their pitch [m]. Throws FabricateError naming --dpi and
// --layer-um beyond Options::max_pixels.
struct SliceSize {
  int width = 0, height = 0, layers = 0;
  double pixel_x = 0, pixel_y = 0;  // [m]
};
SliceSize slice_size(const Fabrication& fabrication);

// `softevo fabricate --check`: what a 3MF holds, read back with lib3mf.
struct CheckedObject {
  std::string name;
  std::uint32_t vertices = 0, triangles = 0;
  bool manifold_and_oriented = false;  // lib3mf's own test
  double volume = 0;                   // [m^3]
  int shells = 0;                      // connected pieces of the surface
  int cavities = 0;                    // shells with negative volume (holes inside the object)
};
struct CheckReport {
  std::vector<std::pair<std::string, std::string>> metadata;
  std::vector<CheckedObject> objects;
  std::string json() const;
  std::string text() const;
};
CheckReport check_3mf(const std::string& path);
bool have_3mf();  // built with lib3mf

std::string mm_text(double metres);  // "12.5 mm": lengths in messages

// What `softevo fabricate` and Robot.fabricate ask for, in their own units and words.
struct Request {
  std::string output;  // OUT.3mf or OUT.stl ("" = none)
  std::string format;  // "3mf", "stl" or "" (by OUT's extension)
  std::string slices;  // directory ("" = none)
  std::string mold;    // directory ("" = none)
  Options options;
  Overwrite overwrite = Overwrite::refuse;
};
// --dpi "X,Y" and --split "z=HEIGHT" [mm] into `options`; FabricateError naming the option.
void parse_dpi(const std::string& text, Options& options);
void parse_split(const std::string& text, Options& options);

// The robot file's name, materials and `evaluation` block as 3MF metadata.
Provenance provenance_of(const RobotFile& robot);

struct Written {
  Fabrication fabrication;
  std::optional<Mold> mold;
  std::vector<std::string> files;  // every file written, slices excepted
  int slices = 0;                  // slice images written
};
// Checks the request, computes every geometry, then writes: nothing is written when any check
// fails. Throws FabricateError (bad input or option), OutputFileError (a target that may not
// be written).
Written fabricate_robot(const RobotFile& robot, const Provenance& provenance,
                        const Request& request);

}  // namespace softevo::fabricate
