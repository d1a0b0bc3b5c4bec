// Trace softevo.trace/1 (io/trace.hpp, docs/trace.md): a round trip of every field, the
// on-disk types the document promises, the defaults for minimal traces of other tools, and
// clear errors for malformed ones.
#include "io/trace.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "io/h5.hpp"
#include "tests/io/tmp_dir.hpp"

namespace softevo::io {
namespace {

using test::TmpDir;

// Two frames of a two-voxel, one-chamber robot; every value distinct.
Trace sample_trace() {
  Trace t;
  t.frames = 2;
  t.voxels = 2;
  t.chambers = 1;
  for (int i = 0; i < 12; ++i) t.positions.push_back(0.001 * i);
  for (int i = 0; i < 16; ++i) t.orientations.push_back(i % 4 == 0 ? 1.0 : 0.0);
  t.pressures = {101325.0, 150000.5};
  t.valve_commands = {0.25f, 0.0f, 1.0f, 0.5f};
  t.time = {0.0, 1.0 / 60.0};
  t.voxel_cells = {0, 0, 0, 1, 0, 0};
  t.voxel_material = {3, 10};
  t.robot_json = "{\"name\": \"sample\"}";
  t.dt = 1e-4;
  t.voxel_size = 0.01;
  t.frame_rate = 60.0;
  t.steps_per_frame = 166;
  t.direction_deg = 45.0;
  t.fitness = 12.5;
  t.status = "ok";
  return t;
}

TEST(Trace, EveryFieldRoundTrips) {
  TmpDir d;
  const Trace t = sample_trace();
  write_trace(d.file("t.h5"), t);
  const Trace r = read_trace(d.file("t.h5"));
  EXPECT_EQ(r.frames, t.frames);
  EXPECT_EQ(r.voxels, t.voxels);
  EXPECT_EQ(r.chambers, t.chambers);
  EXPECT_EQ(r.positions, t.positions);
  EXPECT_EQ(r.orientations, t.orientations);
  EXPECT_EQ(r.pressures, t.pressures);
  EXPECT_EQ(r.valve_commands, t.valve_commands);
  EXPECT_EQ(r.time, t.time);
  EXPECT_EQ(r.voxel_cells, t.voxel_cells);
  EXPECT_EQ(r.voxel_material, t.voxel_material);
  EXPECT_EQ(r.robot_json, t.robot_json);
  EXPECT_EQ(r.dt, t.dt);
  EXPECT_EQ(r.voxel_size, t.voxel_size);
  EXPECT_EQ(r.frame_rate, t.frame_rate);
  EXPECT_EQ(r.steps_per_frame, t.steps_per_frame);
  EXPECT_EQ(r.direction_deg, t.direction_deg);
  EXPECT_EQ(r.fitness, t.fitness);
  EXPECT_EQ(r.status, t.status);
  EXPECT_TRUE(is_trace(d.file("t.h5")));
  // Atomic: no temporary left next to it.
  for (const auto& e : std::filesystem::directory_iterator(d.path))
    EXPECT_EQ(e.path().filename().string(), "t.h5");
}

TEST(Trace, OnDiskTypesAndAttributesAreTheDocumentedOnes) {
  TmpDir d;
  Trace t = sample_trace();
  t.direction_deg.reset();  // gait: no direction attribute
  write_trace(d.file("t.h5"), t);
  const h5::File f = h5::File::open(d.file("t.h5"));
  const auto type_is = [&f](const char* name, hid_t expected) {
    const h5::Id type(H5Dget_type(f.open_dataset(name).id()), H5Tclose);
    return H5Tequal(type.get(), expected) > 0;
  };
  EXPECT_TRUE(type_is("positions", H5T_IEEE_F64LE));
  EXPECT_TRUE(type_is("orientations", H5T_IEEE_F64LE));
  EXPECT_TRUE(type_is("pressures", H5T_IEEE_F64LE));
  EXPECT_TRUE(type_is("valve_commands", H5T_IEEE_F32LE));
  EXPECT_TRUE(type_is("time", H5T_IEEE_F64LE));
  EXPECT_TRUE(type_is("voxel_cells", H5T_STD_I32LE));
  EXPECT_TRUE(type_is("voxel_material", H5T_STD_I32LE));
  EXPECT_EQ(f.open_dataset("positions").dims(), (std::vector<hsize_t>{2, 2, 3}));
  EXPECT_EQ(f.open_dataset("valve_commands").dims(), (std::vector<hsize_t>{2, 2}));
  EXPECT_EQ(f.read_string_attribute("format"), kTraceFormat);
  EXPECT_EQ(f.read_attribute<std::int64_t>("frames"), 2);
  EXPECT_FALSE(f.has_attribute("direction_deg"));
  EXPECT_FALSE(read_trace(d.file("t.h5")).direction_deg.has_value());
}

TEST(Trace, InconsistentTraceIsRefusedBeforeAnythingIsWritten) {
  TmpDir d;
  Trace t = sample_trace();
  t.pressures.pop_back();
  try {
    write_trace(d.file("bad.h5"), t);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pressures"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(d.file("bad.h5")));
  // A failed write keeps the previous trace.
  write_trace(d.file("keep.h5"), sample_trace());
  EXPECT_THROW(write_trace(d.file("keep.h5"), t), std::invalid_argument);
  EXPECT_EQ(read_trace(d.file("keep.h5")).pressures.size(), 2u);
  EXPECT_THROW(write_trace(d.file("no/dir/t.h5"), sample_trace()), std::runtime_error);
}

TEST(Trace, MinimalTraceOfAnotherToolGetsTheDocumentedDefaults) {
  TmpDir d;
  {
    const h5::File f = h5::File::create(d.file("min.h5"));
    f.write_dataset<double>("positions", {3, 1, 3}, std::vector<double>(9, 0.0));
    f.write_dataset<double>("orientations", {3, 1, 4}, {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0});
    f.write_dataset<std::int32_t>("voxel_cells", {1, 3}, {0, 0, 0});
    f.write_dataset<std::int32_t>("voxel_material", {1}, {5});
  }
  const Trace r = read_trace(d.file("min.h5"));
  EXPECT_EQ(r.frames, 3);
  EXPECT_EQ(r.chambers, 0);
  EXPECT_EQ(r.frame_rate, 60.0);
  EXPECT_EQ(r.voxel_size, 0.01);
  EXPECT_EQ(r.time, (std::vector<double>{0.0, 1.0 / 60.0, 2.0 / 60.0}));
  EXPECT_TRUE(r.robot_json.empty());
  EXPECT_FALSE(r.fitness.has_value());
  EXPECT_TRUE(r.status.empty());
  EXPECT_NO_THROW(r.check("min.h5"));
}

TEST(Trace, WrongShapeNamesFileDatasetAndExpectedShape) {
  TmpDir d;
  const std::string path = d.file("shape.h5");
  {
    const h5::File f = h5::File::create(path);
    f.write_dataset<double>("positions", {2, 1, 3}, std::vector<double>(6, 0.0));
    f.write_dataset<double>("orientations", {1, 1, 4}, {1, 0, 0, 0});  // one frame short
    f.write_dataset<std::int32_t>("voxel_cells", {1, 3}, {0, 0, 0});
    f.write_dataset<std::int32_t>("voxel_material", {1}, {5});
  }
  try {
    read_trace(path);
    ADD_FAILURE() << "no exception";
  } catch (const h5::Error& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.object(), "/orientations");
    EXPECT_NE(e.reason().find("[2, 1, 4]"), std::string::npos) << e.what();
  }
  std::ofstream(d.file("text.h5")) << "not hdf5";
  EXPECT_FALSE(is_trace(d.file("text.h5")));
  EXPECT_THROW(read_trace(d.file("text.h5")), std::runtime_error);
  EXPECT_THROW(read_trace(d.file("missing.h5")), std::runtime_error);
}

// Issue 39: a trace with inf positions made `softevo view --export-html` say only
// "vector::reserve" and ended the live server when a page connected. Every value a simulation
// cannot have recorded is refused on reading, naming the file, the value and the rule; the
// writer (which only a simulation feeds) writes what it is given, so these files exist.
TEST(Trace, ValuesNoSimulationRecordsAreRefusedOnReadingNamingThem) {
  TmpDir d;
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Trace bumpy = sample_trace();
  bumpy.terrain = Trace::Terrain{};
  bumpy.terrain->kind = "bumps";
  bumpy.terrain->seed = "00000000000000ff";
  bumpy.terrain->shape.amplitude = 0.01;
  bumpy.terrain->shape.correlation_length = 0.05;
  // A chamber that encloses no volume has no pressure (NaN), and the controller's commands then
  // follow: a simulation records them, so they are read.
  bumpy.pressures[1] = nan;
  bumpy.valve_commands[2] = std::numeric_limits<float>::quiet_NaN();
  write_trace(d.file("good.h5"), bumpy);
  EXPECT_NO_THROW(read_trace(d.file("good.h5")));

  const std::vector<std::pair<std::string, std::function<void(Trace&)>>> bad = {
      {"positions [m] value 4 = inf", [&](Trace& t) { t.positions[4] = inf; }},
      {"positions [m] value 0 = nan", [&](Trace& t) { t.positions[0] = nan; }},
      {"positions [m] value 11 = 1e+300", [&](Trace& t) { t.positions[11] = 1e300; }},
      {"orientations value 2 = nan", [&](Trace& t) { t.orientations[2] = nan; }},
      {"quaternion 1 length = 0", [&](Trace& t) { t.orientations[4] = 0.0; }},
      {"voxel_size [m] = -0.01", [&](Trace& t) { t.voxel_size = -0.01; }},
      {"frame_rate [Hz] = 0", [&](Trace& t) { t.frame_rate = 0.0; }},
      {"dt [s] = nan", [&](Trace& t) { t.dt = nan; }},
      {"direction_deg [deg] = 400", [&](Trace& t) { t.direction_deg = 400.0; }},
      {"fitness = inf", [&](Trace& t) { t.fitness = inf; }},
      {"voxel_cells value 3 = 70", [&](Trace& t) { t.voxel_cells[3] = 70; }},
      {"voxel_material value 0 = 0", [&](Trace& t) { t.voxel_material[0] = 0; }},
      {"time [s] of frame 1 = -1", [&](Trace& t) { t.time[1] = -1.0; }},
      {"terrain_amplitude [m] = 1e+300", [&](Trace& t) { t.terrain->shape.amplitude = 1e300; }},
      {"terrain_correlation_length [m] = 0",
       [&](Trace& t) { t.terrain->shape.correlation_length = 0.0; }},
      {"terrain_bumps_start_x [m] = -inf", [&](Trace& t) { t.terrain->bumps_start_x = -inf; }},
      {"terrain_row_x [m] value 0 = nan", [&](Trace& t) { t.terrain->row_x = {nan}; }},
  };
  for (const auto& [what, spoil] : bad) {
    Trace t = bumpy;
    spoil(t);
    const std::string path = d.file("bad.h5");
    write_trace(path, t, Overwrite::replace);
    try {
      read_trace(path);
      ADD_FAILURE() << what << ": no exception";
    } catch (const std::runtime_error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
      EXPECT_NE(message.find("must be"), std::string::npos) << message;
    }
  }
}

}  // namespace
}  // namespace softevo::io
