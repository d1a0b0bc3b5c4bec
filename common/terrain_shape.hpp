// The numbers that shape a heightfield ground (docs/model.md §2.8a), written once. The config
// (TerrainConfig::shape, with the config's defaults), the physics (physics::TerrainParams::shape)
// and traces (io::Trace::Terrain::shape) each hold a TerrainShape, so copying between them is
// one assignment; the config keys and the trace attributes are derived from
// kTerrainShapeFields. A new number is one member here and one row there.
#pragma once

#include <array>
#include <cstdint>

namespace softevo {

enum class HeightfieldKind : std::uint8_t { bumps, steps, slope };  // terrain.heightfield

struct TerrainShape {
  double amplitude = 0.0;           // bumps: largest height above / below the plane [m]
  double correlation_length = 0.0;  // bumps: grid spacing of the value noise [m]
  double step_height = 0.0;         // steps: rise of each step [m]
  double step_spacing = 0.0;        // steps: tread length along +x [m]
  double slope_angle = 0.0;         // slope: inclination [deg], > 0 uphill
  double slope_direction = 0.0;     // slope: uphill direction from +x towards +y [deg]
  bool operator==(const TerrainShape&) const = default;
};

// One number of TerrainShape: where it lives, its config key ([terrain] section, docs/model.md
// §2.8a) and range, its trace attribute (docs/trace.md) and the heightfield that uses it.
struct TerrainShapeField {
  double TerrainShape::*member;
  const char* key;
  const char* trace_attribute;
  const char* unit;
  HeightfieldKind heightfield;
  double min;  // config range, inclusive unless min_exclusive
  double max;
  bool min_exclusive = false;
};

// In config key order: the order of the canonical config text (and so of the config hash).
inline constexpr std::array<TerrainShapeField, 6> kTerrainShapeFields = {{
    {.member = &TerrainShape::amplitude,
     .key = "amplitude",
     .trace_attribute = "terrain_amplitude",
     .unit = "m",
     .heightfield = HeightfieldKind::bumps,
     .min = 0,
     .max = 1},
    {.member = &TerrainShape::correlation_length,
     .key = "correlation_length",
     .trace_attribute = "terrain_correlation_length",
     .unit = "m",
     .heightfield = HeightfieldKind::bumps,
     .min = 0,
     .max = 100,
     .min_exclusive = true},
    {.member = &TerrainShape::step_height,
     .key = "step_height",
     .trace_attribute = "terrain_step_height",
     .unit = "m",
     .heightfield = HeightfieldKind::steps,
     .min = 0,
     .max = 1},
    {.member = &TerrainShape::step_spacing,
     .key = "step_spacing",
     .trace_attribute = "terrain_step_spacing",
     .unit = "m",
     .heightfield = HeightfieldKind::steps,
     .min = 0,
     .max = 100,
     .min_exclusive = true},
    {.member = &TerrainShape::slope_angle,
     .key = "slope_angle",
     .trace_attribute = "terrain_slope_angle_deg",
     .unit = "deg",
     .heightfield = HeightfieldKind::slope,
     .min = -60,
     .max = 60},
    {.member = &TerrainShape::slope_direction,
     .key = "slope_direction",
     .trace_attribute = "terrain_slope_direction_deg",
     .unit = "deg",
     .heightfield = HeightfieldKind::slope,
     .min = -360,
     .max = 360},
}};

}  // namespace softevo
