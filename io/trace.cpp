// HDF5 implementation of the trace (schema: docs/trace.md) over the RAII layer of io/h5.hpp.
#include "io/trace.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/config.hpp"
#include "common/safe_write.hpp"
#include "io/h5.hpp"

namespace softevo::io {
namespace {

using h5::Charset;

// Defaults for traces written by other tools (docs/trace.md): one frame per 60 Hz control
// frame, a 1 cm lattice.
constexpr double kDefaultFrameRate = 60.0;  // [Hz]
constexpr double kDefaultVoxelSize = 0.01;  // [m]

void expect_size(std::size_t actual, std::int64_t expected, const char* name,
                 const std::string& where) {
  if (actual != static_cast<std::size_t>(expected))
    throw std::invalid_argument(where + ": " + name + " has " + std::to_string(actual) +
                                " values, expected " + std::to_string(expected));
}

[[noreturn]] void bad_shape(const h5::Where& where, const std::string& expected) {
  where.fail("read dataset", "shape must be " + expected);
}

std::string shape(std::initializer_list<std::int64_t> dims) {
  std::string s = "[";
  for (const std::int64_t d : dims) s += (s.size() > 1 ? ", " : "") + std::to_string(d);
  return s + "]";
}

// The terrain's number attributes in file order (docs/trace.md), as (name, member of `g`):
// each heightfield's numbers (common/terrain_shape.hpp) followed by where that ground starts,
// then the rows' y span. One list for writing (`g` const) and reading, so the two cannot drift.
template <class TraceTerrain>
auto terrain_numbers(TraceTerrain& g) {
  using Number = decltype(&g.row_y_min);  // double* or const double*
  struct Start {
    HeightfieldKind heightfield;
    const char* name;
    Number value;
  };
  const Start starts[] = {{HeightfieldKind::bumps, "terrain_bumps_start_x", &g.bumps_start_x},
                          {HeightfieldKind::steps, "terrain_first_riser_x", &g.first_riser_x},
                          {HeightfieldKind::slope, "terrain_slope_start", &g.slope_start}};
  std::vector<std::pair<const char*, Number>> numbers;
  for (const Start& start : starts) {
    for (const TerrainShapeField& f : kTerrainShapeFields)
      if (f.heightfield == start.heightfield)
        numbers.emplace_back(f.trace_attribute, &(g.shape.*f.member));
    numbers.emplace_back(start.name, start.value);
  }
  numbers.emplace_back("terrain_row_y_min", &g.row_y_min);
  numbers.emplace_back("terrain_row_y_max", &g.row_y_max);
  return numbers;
}

}  // namespace

void Trace::check(const std::string& where) const {
  if (frames < 0 || voxels < 0 || chambers < 0)
    throw std::invalid_argument(where + ": negative frame, voxel or chamber count");
  expect_size(positions.size(), frames * voxels * 3, "positions", where);
  expect_size(orientations.size(), frames * voxels * 4, "orientations", where);
  expect_size(pressures.size(), frames * chambers, "pressures", where);
  expect_size(valve_commands.size(), frames * 2 * chambers, "valve_commands", where);
  expect_size(time.size(), frames, "time", where);
  expect_size(voxel_cells.size(), voxels * 3, "voxel_cells", where);
  expect_size(voxel_material.size(), voxels, "voxel_material", where);
}

namespace {

// "`what` = value: must be `rule`" with the value in its shortest round-trip form.
[[noreturn]] void bad_value(const std::string& where, const std::string& what, double value,
                            const std::string& rule) {
  throw std::invalid_argument(where + ": " + what + " = " + toml_number(value) + ": must be " +
                              rule + " (docs/trace.md \"Limits\")");
}

void check_range(const std::string& where, const std::string& what, double value, double lo,
                 double hi, bool lo_exclusive = false) {
  const bool above = lo_exclusive ? value > lo : value >= lo;
  if (std::isfinite(value) && above && value <= hi) return;
  char rule[96];
  std::snprintf(rule, sizeof rule, "finite, in %s%g, %g]", lo_exclusive ? "(" : "[", lo, hi);
  bad_value(where, what, value, rule);
}

// Every value of `values` finite and in [lo, hi]; the error names the first one that is not.
template <class T>
void check_each(const std::string& where, const char* dataset, const std::vector<T>& values,
                double lo, double hi) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    const auto v = static_cast<double>(values[i]);
    if (!(std::isfinite(v) && v >= lo && v <= hi))
      check_range(where, std::string(dataset) + " value " + std::to_string(i), v, lo, hi);
  }
}

}  // namespace

void Trace::check_values(const std::string& where) const {
  constexpr double kPos = TraceLimits::position_m;
  check_range(where, "attribute voxel_size [m]", voxel_size, 0.0, TraceLimits::max_voxel_size_m,
              true);
  check_range(where, "attribute frame_rate [Hz]", frame_rate, 0.0, TraceLimits::max_frame_rate_hz,
              true);
  check_range(where, "attribute dt [s]", dt, 0.0, TraceLimits::max_dt_s);
  if (steps_per_frame < 0)
    bad_value(where, "attribute steps_per_frame", static_cast<double>(steps_per_frame), ">= 0");
  if (direction_deg)
    check_range(where, "attribute direction_deg [deg]", *direction_deg, -180.0, 180.0);
  if (fitness && !std::isfinite(*fitness))
    bad_value(where, "attribute fitness", *fitness, "finite");
  for (std::size_t i = 0; i < voxel_cells.size(); ++i)
    if (voxel_cells[i] < 0 || voxel_cells[i] >= TraceLimits::lattice_cells)
      bad_value(where, "voxel_cells value " + std::to_string(i), voxel_cells[i],
                "in [0, " + std::to_string(TraceLimits::lattice_cells) + ")");
  check_each(where, "voxel_material", voxel_material, 1, TraceLimits::materials);
  check_each(where, "positions [m]", positions, -kPos, kPos);
  check_each(where, "orientations", orientations, -2.0, 2.0);
  // A unit quaternion (never renormalised in the simulation, so a little off): one of length
  // far from 1 turns a cube into nothing or into a cube many times its size.
  for (std::size_t q = 0; q + 3 < orientations.size(); q += 4) {
    const double norm = std::sqrt(
        orientations[q] * orientations[q] + orientations[q + 1] * orientations[q + 1] +
        orientations[q + 2] * orientations[q + 2] + orientations[q + 3] * orientations[q + 3]);
    if (!(norm >= 0.5 && norm <= 1.5))
      bad_value(where, "orientations quaternion " + std::to_string(q / 4) + " length", norm,
                "about 1 (a unit quaternion)");
  }
  // Pressures and valve commands are not checked: a simulation records NaN for a chamber that
  // encloses no volume (p = n / V, docs/model.md §3.3), and the controller's commands then follow
  // the NaN sensor input. They only colour chambers and fill plots, which show such a value as
  // none.
  for (std::size_t f = 0; f < time.size(); ++f) {
    if (!std::isfinite(time[f]) || time[f] < 0.0)
      bad_value(where, "time [s] of frame " + std::to_string(f), time[f], "finite and >= 0");
    if (f > 0 && time[f] < time[f - 1])
      bad_value(where, "time [s] of frame " + std::to_string(f), time[f],
                "at least the time of the frame before (times never go back)");
  }
  if (!terrain) return;
  const Terrain& g = *terrain;
  // The numbers of the ground's own heightfield within the config's ranges
  // (common/terrain_shape.hpp); every position within the positions' limit.
  for (const TerrainShapeField& f : kTerrainShapeFields) {
    const bool used = (g.kind == "bumps" && f.heightfield == HeightfieldKind::bumps) ||
                      (g.kind == "steps" && f.heightfield == HeightfieldKind::steps) ||
                      (g.kind == "slope" && f.heightfield == HeightfieldKind::slope);
    if (used)
      check_range(where, std::string("attribute ") + f.trace_attribute + " [" + f.unit + "]",
                  g.shape.*f.member, f.min, f.max, f.min_exclusive);
  }
  for (const auto& [name, value] : terrain_numbers(g))
    check_range(where, std::string("attribute ") + name + " [m]", *value, -kPos, kPos);
  check_each(where, "terrain_row_x [m]", g.row_x, -kPos, kPos);
}

void write_trace(const std::string& path, const Trace& t, Overwrite overwrite) {
  t.check(path);
  const auto frames = static_cast<hsize_t>(t.frames);
  const auto voxels = static_cast<hsize_t>(t.voxels);
  const auto chambers = static_cast<hsize_t>(t.chambers);
  // Like every output file of a command (docs/output-files.md).
  AtomicOutput out(path, overwrite);
  h5::File file = h5::File::create(out.temp_path(), nullptr, path);
  file.write_dataset<double>("positions", {frames, voxels, 3}, t.positions);
  file.write_dataset<double>("orientations", {frames, voxels, 4}, t.orientations);
  file.write_dataset<double>("pressures", {frames, chambers}, t.pressures);
  file.write_dataset<float>("valve_commands", {frames, 2 * chambers}, t.valve_commands);
  file.write_dataset<double>("time", {frames}, t.time);
  file.write_dataset<std::int32_t>("voxel_cells", {voxels, 3}, t.voxel_cells);
  file.write_dataset<std::int32_t>("voxel_material", {voxels}, t.voxel_material);
  file.write_string_dataset("robot_json", t.robot_json, Charset::ascii);
  file.write_string_attribute("format", kTraceFormat, Charset::ascii);
  file.write_attribute<double>("dt", t.dt);
  file.write_attribute<double>("voxel_size", t.voxel_size);
  file.write_attribute<std::int64_t>("frames", t.frames);
  file.write_attribute<double>("frame_rate", t.frame_rate);
  file.write_attribute<std::int64_t>("steps_per_frame", t.steps_per_frame);
  if (t.direction_deg) file.write_attribute<double>("direction_deg", *t.direction_deg);
  if (t.fitness) file.write_attribute<double>("fitness", *t.fitness);
  file.write_string_attribute("status", t.status, Charset::ascii);
  if (t.terrain) {
    const Trace::Terrain& g = *t.terrain;
    file.write_string_attribute("terrain_kind", g.kind, Charset::ascii);
    file.write_string_attribute("terrain_seed", g.seed, Charset::ascii);
    for (const auto& [name, value] : terrain_numbers(g)) file.write_attribute<double>(name, *value);
    file.write_dataset<double>("terrain_row_x", {static_cast<hsize_t>(g.row_x.size())}, g.row_x);
  }
  file.close();
  out.commit();
}

Trace read_trace(const std::string& path) {
  const h5::File file = h5::File::open(path);
  Trace t;
  // Every extent is checked against the counts already read and TraceLimits before the
  // dataset is read, so a damaged extent costs an error, not its allocation.
  const auto beyond = [&](const std::string& dataset, const std::string& what, std::int64_t limit) {
    file.where().child(dataset).fail(
        "read dataset",
        what + " beyond the limit of " + std::to_string(limit) + " (docs/trace.md \"Limits\")");
  };
  const auto within = [&](const std::string& dataset, hsize_t extent, std::int64_t limit,
                          const std::string& what) {
    if (extent > static_cast<hsize_t>(limit))
      beyond(dataset, std::to_string(extent) + " " + what, limit);
    return static_cast<std::int64_t>(extent);
  };
  h5::Dataset cells = file.open_dataset("voxel_cells");
  std::vector<hsize_t> dims = cells.dims();
  if (dims.size() != 2 || dims[1] != 3) bad_shape(cells.where(), "[voxels, 3]");
  t.voxels = within("voxel_cells", dims[0], TraceLimits::voxels, "voxels");
  t.voxel_cells = cells.read<std::int32_t>();
  if (std::any_of(t.voxel_cells.begin(), t.voxel_cells.end(), [](std::int32_t c) { return c < 0; }))
    cells.where().fail("read dataset", "negative voxel cell index");
  // `name` must have exactly the shape `expected` (checked before it is read).
  const auto exact = [&](const std::string& name, std::initializer_list<std::int64_t> expected) {
    h5::Dataset ds = file.open_dataset(name);
    if (ds.dims() != std::vector<hsize_t>(expected.begin(), expected.end()))
      bad_shape(ds.where(), shape(expected));
    return ds;
  };
  t.voxel_material = exact("voxel_material", {t.voxels}).read<std::int32_t>();

  h5::Dataset positions = file.open_dataset("positions");
  dims = positions.dims();
  if (dims.size() != 3 || dims[1] != static_cast<hsize_t>(t.voxels) || dims[2] != 3)
    bad_shape(positions.where(), "[frames, " + std::to_string(t.voxels) + ", 3]");
  t.frames = within("positions", dims[0], TraceLimits::frames, "frames");
  t.positions = positions.read<double>();
  t.orientations = exact("orientations", {t.frames, t.voxels, 4}).read<double>();

  if (file.has_link("pressures")) {
    h5::Dataset pressures = file.open_dataset("pressures");
    dims = pressures.dims();
    if (dims.size() != 2 || dims[0] != static_cast<hsize_t>(t.frames))
      bad_shape(pressures.where(), "[" + std::to_string(t.frames) + ", chambers]");
    t.chambers = within("pressures", dims[1], TraceLimits::chambers, "chambers");
    t.pressures = pressures.read<double>();
  }
  if (file.has_link("valve_commands")) {
    t.valve_commands = exact("valve_commands", {t.frames, 2 * t.chambers}).read<float>();
  } else {
    // Within the file's size: frames x chambers values of pressure were read.
    t.valve_commands.assign(static_cast<std::size_t>(t.frames * 2 * t.chambers), 0.0f);
  }

  t.frame_rate = file.has_attribute("frame_rate") ? file.read_attribute<double>("frame_rate")
                                                  : kDefaultFrameRate;
  if (file.has_link("time")) {
    t.time = exact("time", {t.frames}).read<double>();
  } else {
    t.time.reserve(static_cast<std::size_t>(t.frames));
    for (std::int64_t f = 0; f < t.frames; ++f)
      t.time.push_back(static_cast<double>(f) / t.frame_rate);
  }
  // Early traces kept the robot file in an attribute.
  constexpr auto kRobotBytes = static_cast<std::size_t>(TraceLimits::robot_json_bytes);
  constexpr auto kStringBytes = static_cast<std::size_t>(TraceLimits::string_bytes);
  if (file.has_link("robot_json")) {
    t.robot_json = file.open_dataset("robot_json").read_string(kRobotBytes);
  } else if (file.has_attribute("robot_json")) {
    t.robot_json = file.read_string_attribute("robot_json", kRobotBytes);
  }
  t.voxel_size = file.has_attribute("voxel_size") ? file.read_attribute<double>("voxel_size")
                                                  : kDefaultVoxelSize;
  if (file.has_attribute("dt")) t.dt = file.read_attribute<double>("dt");
  if (file.has_attribute("steps_per_frame"))
    t.steps_per_frame = file.read_attribute<std::int64_t>("steps_per_frame");
  if (file.has_attribute("direction_deg"))
    t.direction_deg = file.read_attribute<double>("direction_deg");
  if (file.has_attribute("fitness")) t.fitness = file.read_attribute<double>("fitness");
  if (file.has_attribute("status")) t.status = file.read_string_attribute("status", kStringBytes);
  if (file.has_attribute("terrain_kind")) {
    Trace::Terrain g;
    g.kind = file.read_string_attribute("terrain_kind", kStringBytes);
    g.seed = file.read_string_attribute("terrain_seed", kStringBytes);
    for (const auto& [name, value] : terrain_numbers(g)) *value = file.read_attribute<double>(name);
    if (file.has_link("terrain_row_x"))
      g.row_x = file.open_dataset("terrain_row_x").read<double>(64);
    t.terrain = std::move(g);
  }
  try {
    t.check_values(path);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  return t;
}

bool is_trace(const std::string& path) {
  try {
    return h5::File::is_hdf5(path) && h5::File::open(path).has_link("positions");
  } catch (const h5::DamagedFileError& e) {
    throw std::runtime_error(e.what());
  } catch (const h5::Error&) {
    return false;
  }
}

}  // namespace softevo::io
