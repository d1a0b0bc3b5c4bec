#include "common/map_grid.hpp"

#include <cmath>
#include <stdexcept>

namespace softevo {

const std::vector<std::string>& map_descriptor_names() {
  static const std::vector<std::string> names = {
      "chamber_count", "actuated_fraction", "void_fraction", "voxels",
      "height",        "elongation",        "mean_speed"};
  return names;
}

std::int64_t MapGrid::cells() const {
  std::int64_t n = 1;
  for (const MapAxis& a : axes) n *= a.bins;
  return n;
}

std::int64_t MapGrid::bin(std::size_t a, double value) const {
  if (std::isnan(value)) return -1;
  const MapAxis& axis = axes.at(a);
  const double position =
      (value - axis.min) / (axis.max - axis.min) * static_cast<double>(axis.bins);
  if (!(position >= 0.0)) return 0;  // below min (or -inf)
  if (position >= static_cast<double>(axis.bins)) return axis.bins - 1;
  return static_cast<std::int64_t>(std::floor(position));
}

std::int64_t MapGrid::cell(const std::vector<double>& values) const {
  if (values.size() != axes.size())
    throw std::invalid_argument("map cell: " + std::to_string(values.size()) + " values for " +
                                std::to_string(axes.size()) + " descriptors");
  std::vector<std::int64_t> b(axes.size());
  for (std::size_t a = 0; a < axes.size(); ++a) {
    b[a] = bin(a, values[a]);
    if (b[a] < 0) return -1;
  }
  return cell_of_bins(b);
}

std::int64_t MapGrid::cell_of_bins(const std::vector<std::int64_t>& bins) const {
  if (bins.size() != axes.size())
    throw std::invalid_argument("map cell: " + std::to_string(bins.size()) + " bins for " +
                                std::to_string(axes.size()) + " descriptors");
  std::int64_t c = 0;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    if (bins[a] < 0 || bins[a] >= axes[a].bins)
      throw std::invalid_argument("map cell: bin " + std::to_string(bins[a]) + " of " +
                                  axes[a].name + " outside [0, " + std::to_string(axes[a].bins) +
                                  ")");
    c = c * axes[a].bins + bins[a];
  }
  return c;
}

std::vector<std::int64_t> MapGrid::coordinates(std::int64_t cell) const {
  std::vector<std::int64_t> b(axes.size());
  for (std::size_t a = axes.size(); a-- > 0;) {
    b[a] = cell % axes[a].bins;
    cell /= axes[a].bins;
  }
  return b;
}

MapGrid map_grid(const Config& config, const std::string& source) {
  const MapElitesConfig& m = config.map_elites;
  const auto fail = [&](const std::string& what) { throw ConfigError(source + ": " + what); };
  const auto entries = [](std::size_t count) {
    return std::to_string(count) + (count == 1 ? " entry" : " entries");
  };
  const std::size_t n = m.descriptors.size();
  if (n < 1 || n > 3) fail("map_elites.descriptors has " + entries(n) + "; a map has 1-3");
  const auto same_length = [&](std::size_t size, const char* key) {
    if (size != n)
      fail(std::string(key) + " has " + entries(size) + ", map_elites.descriptors " +
           std::to_string(n) + " (one per descriptor)");
  };
  same_length(m.min.size(), "map_elites.min");
  same_length(m.max.size(), "map_elites.max");
  same_length(m.bins.size(), "map_elites.bins");
  MapGrid grid;
  std::int64_t cells = 1;
  const auto& names = map_descriptor_names();
  for (std::size_t a = 0; a < n; ++a) {
    const std::string idx = "[" + std::to_string(a) + "]";
    MapAxis axis;
    axis.name = m.descriptors[a];
    std::size_t k = 0;
    while (k < names.size() && names[k] != axis.name) ++k;
    if (k == names.size())
      fail("map_elites.descriptors" + idx + " = \"" + axis.name + "\" is unknown");
    axis.descriptor = static_cast<MapDescriptor>(k);
    axis.min = m.min[a];
    axis.max = m.max[a];
    axis.bins = m.bins[a];
    if (!std::isfinite(axis.min) || !std::isfinite(axis.max) || !(axis.min < axis.max))
      fail("map_elites.min" + idx + " = " + toml_number(axis.min) +
           " must be below map_elites.max" + idx + " = " + toml_number(axis.max) +
           " (descriptor \"" + axis.name + "\")");
    if (axis.bins < 1)
      fail("map_elites.bins" + idx + " = " + std::to_string(axis.bins) +
           " must be at least 1 (descriptor \"" + axis.name + "\")");
    if (axis.descriptor == MapDescriptor::mean_speed && config.task.kind != TaskKind::gait)
      fail("map_elites.descriptors" + idx +
           " = \"mean_speed\" needs task.kind = \"gait\" (a distance per second), got task.kind = "
           "\"" +
           std::string(to_string(config.task.kind)) + "\"");
    // Checked axis by axis, so the product cannot overflow (bins <= 10^9, cells <= 10^7).
    cells *= axis.bins;
    if (cells > m.max_cells) {
      std::string bins;
      for (std::size_t b = 0; b < n; ++b) bins += (b ? ", " : "") + std::to_string(m.bins[b]);
      fail("map_elites.bins = [" + bins +
           "] gives more cells than map_elites.max_cells = " + std::to_string(m.max_cells));
    }
    grid.axes.push_back(std::move(axis));
  }
  return grid;
}

}  // namespace softevo
