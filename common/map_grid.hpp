// The grid of MAP-Elites (docs/model.md §8.12.2): 1-3 named descriptors, each with its range
// and number of bins, from the config's [map_elites]. Plain data and index arithmetic; the
// descriptor values themselves are computed by evo/map_elites.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/config.hpp"

namespace softevo {

// The descriptors a map can have, in the order of map_descriptor_names() (§8.12.2 gives each
// formula and unit).
enum class MapDescriptor : std::uint8_t {
  chamber_count,      // chambers of the developed body [-]
  actuated_fraction,  // chamber voxels / voxels [-]
  void_fraction,      // empty cells / cells of the query lattice [-]
  voxels,             // voxels of the body [-]
  height,             // extent of the body along z [m]
  elongation,         // longest / shortest extent of the body's bounding box [-]
  mean_speed,         // distance travelled / task.eval_seconds [m/s] (gait only)
};
const std::vector<std::string>& map_descriptor_names();

struct MapAxis {
  MapDescriptor descriptor = MapDescriptor::chamber_count;
  std::string name;
  double min = 0.0;  // inclusive
  double max = 1.0;  // exclusive (a value outside [min, max) lands in the nearest edge bin)
  std::int64_t bins = 1;
};

struct MapGrid {
  std::vector<MapAxis> axes;
  std::int64_t cells() const;
  // Bin of `value` on axis `a`: floor((value - min) / (max - min) * bins) clamped to
  // [0, bins - 1]; -1 for a value that is not a number.
  std::int64_t bin(std::size_t a, double value) const;
  // Row-major cell index (the first axis varies slowest) of one value per axis; -1 when any
  // value is not a number.
  std::int64_t cell(const std::vector<double>& values) const;
  std::vector<std::int64_t> coordinates(std::int64_t cell) const;
  // Cell of per-axis bins; throws std::invalid_argument naming the axis when one is out of range.
  std::int64_t cell_of_bins(const std::vector<std::int64_t>& bins) const;
};

// The grid of `config` ([map_elites]); throws ConfigError naming the key for an inconsistent
// one: lists of different lengths, more than 3 descriptors, min >= max, more cells than
// map_elites.max_cells, a behavioural descriptor of a task without a distance.
MapGrid map_grid(const Config& config, const std::string& source = "<config>");

}  // namespace softevo
