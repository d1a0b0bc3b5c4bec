// `softevo fabricate ROBOT -o OUT.3mf|OUT.stl [--slices DIR] [--mold DIR]` and
// `softevo fabricate --check OUT.3mf`: an evolved robot for the 3-D printer and for silicone
// casting (fabricate/fabricate.hpp, docs/fabrication.md). ROBOT is a robot file or a run archive
// (--generation, --id / --best as export and render take them). Every geometry and every option
// is checked before the first file is written; each file is written atomically, an existing one
// replaced only with --force.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_identity.hpp"
#include "common/robot.hpp"
#include "fabricate/fabricate.hpp"
#include "io/archive.hpp"
#include "motion/robot_source.hpp"
#include "tools/commands.hpp"
#include "tools/elite_cell.hpp"

namespace softevo::cli {

namespace {

struct FabricateArgs {
  std::string input;
  std::string output;
  std::string format;  // "" = by the output's extension
  std::optional<std::int64_t> generation;
  std::optional<std::int64_t> id;
  bool best = false;
  std::string cell;  // a MAP-Elites run: the elite of this cell (tools/elite_cell.hpp)
  double scale = 1.0;
  double channel_mm = 1.5;
  std::string slices;
  std::string dpi = "600,300";
  double layer_um = 30.0;
  std::string mold;
  double wall_mm = 3.0;
  std::string split;
  std::string check;
  bool force = false;
  bool json = false;
};

// The robot and what the 3MF metadata says of it.
std::pair<RobotFile, fabricate::Provenance> load_robot(const FabricateArgs& a) {
  if (io::is_run_archive(a.input)) {
    const motion::ArchivedIndividual ind =
        motion::archived_individual(a.input, a.generation, a.best ? std::nullopt : a.id);
    RobotFile robot = motion::robot_of(ind);
    fabricate::Provenance pv = fabricate::provenance_of(robot);
    pv.genome_id = ind.id;
    pv.generation = ind.generation;
    pv.run = a.input;
    pv.config_hash = hash_hex(text_hash(ind.config_text));
    pv.fitness = ind.fitness;
    return {robot, pv};
  }
  if (a.generation || a.id || a.best)
    throw std::invalid_argument(
        "fabricate: --generation, --id and --best select from a run "
        "archive; " +
        a.input + " is a robot file");
  RobotFile robot = read_robot_file(a.input);
  if (robot.name.empty()) robot.name = std::filesystem::path(a.input).stem().string();
  return {robot, fabricate::provenance_of(robot)};
}

int run_check(const FabricateArgs& a) {
  const fabricate::CheckReport report = fabricate::check_3mf(a.check);
  bool ok = !report.objects.empty();
  for (const auto& o : report.objects) ok = ok && o.manifold_and_oriented && o.volume > 0;
  if (a.json) {
    std::printf("%s\n", report.json().c_str());
  } else {
    std::printf("%s%s: %zu objects, %s\n", report.text().c_str(), a.check.c_str(),
                report.objects.size(),
                ok ? "all closed, manifold and oriented, positive volumes" : "NOT all valid");
  }
  return ok ? kExitOk : kExitMismatch;
}

int run_fabricate(const FabricateArgs& a) {
  if (a.input.empty()) throw std::invalid_argument("fabricate: ROBOT is required (or --check)");
  fabricate::Request request;
  request.output = a.output;
  request.format = a.format;
  request.slices = a.slices;
  request.mold = a.mold;
  request.overwrite = a.force ? Overwrite::replace : Overwrite::refuse;
  fabricate::Options& o = request.options;
  o.scale = a.scale;
  o.channel_diameter = a.channel_mm * 1e-3;
  o.wall = a.wall_mm * 1e-3;
  o.layer = a.layer_um * 1e-6;
  fabricate::parse_dpi(a.dpi, o);
  if (!a.split.empty()) fabricate::parse_split(a.split, o);
  const auto [robot, provenance] = load_robot(a);
  const fabricate::Written w = fabricate::fabricate_robot(robot, provenance, request);
  const fabricate::Fabrication& fab = w.fabrication;
  if (a.json) {
    nlohmann::ordered_json j;
    j["input"] = a.input;
    j["robot"] = provenance.name;
    j["voxels"] = fab.voxel_count;
    j["chambers"] = fab.inlets.size();
    j["voxel_size_mm"] = fab.voxel_size * 1e3;
    j["groups"] = nlohmann::ordered_json::array();
    for (const auto& g : fab.groups) {
      j["groups"].push_back({{"name", g.name},
                             {"voxels", g.voxels},
                             {"triangles", g.mesh.triangles.size()},
                             {"volume_mm3", g.mesh.volume() * 1e9}});
    }
    j["channel_volume_mm3"] = fab.channel_volume * 1e9;
    j["files"] = w.files;
    if (!a.slices.empty()) j["slices"] = w.slices;
    if (w.mold) j["split_z_mm"] = w.mold->split_z * 1e3;
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s: %s\n", provenance.name.c_str(), fab.summary().c_str());
    for (const auto& in : fab.inlets) {
      std::printf("  chamber %d: inlet through %d wall voxels, mouth at (%.4g, %.4g, %.4g) mm\n",
                  in.chamber, in.wall_cells, in.mouth.x() * 1e3, in.mouth.y() * 1e3,
                  in.mouth.z() * 1e3);
    }
    for (const auto& p : w.files) std::printf("wrote %s\n", p.c_str());
    if (!a.slices.empty())
      std::printf("wrote %d slices and palette.json to %s\n", w.slices, a.slices.c_str());
  }
  return kExitOk;
}

}  // namespace

void register_fabricate(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "fabricate", "export a robot for 3-D printing and silicone casting (docs/fabrication.md)");
  auto a = std::make_shared<FabricateArgs>();
  cmd->add_option("ROBOT", a->input, "robot file (.json) or run archive (.h5)");
  cmd->add_option("-o,--output,--out", a->output,
                  "OUT.3mf (one object per material group) or OUT.stl (OUT-<group>.stl each)");
  cmd->add_option("--format", a->format, "3mf or stl (default: by the extension of OUT)")
      ->check(CLI::IsMember({"3mf", "stl"}));
  add_individual_options(*cmd, a->generation, a->id, a->best, &a->cell, "archive: ");
  cmd->add_option("--scale", a->scale, "printed voxel edge = voxel_size x SCALE (default 1)")
      ->check(finite_in(1e-6, 1e6));
  cmd->add_option("--channel-diameter", a->channel_mm,
                  "side of each chamber's square inlet channel [mm] (default 1.5)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--slices", a->slices, "write material-per-pixel PNG layers to DIR");
  cmd->add_option("--dpi", a->dpi, "slice pixels per inch X,Y (default 600,300)");
  cmd->add_option("--layer-um", a->layer_um, "slice thickness [um] (default 30)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--mold", a->mold, "write a two-part casting mold and its cores to DIR");
  cmd->add_option("--wall", a->wall_mm, "mold material around the body [mm] (default 3)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--split", a->split,
                  "mold split plane z=HEIGHT [mm above the body's bottom] (default: the widest "
                  "horizontal section)");
  cmd->add_option("--check", a->check,
                  "read OUT.3mf back (lib3mf) and report its objects, volumes and cavities");
  cmd->add_flag("--force", a->force, "replace existing output files");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->callback([&exit_code, a] {
    if (a->check.empty()) select_cell(a->input, a->cell, a->generation, a->id);
    exit_code = a->check.empty() ? run_fabricate(*a) : run_check(*a);
  });
}

}  // namespace softevo::cli
