// One fabrication request, as `softevo fabricate` and Robot.fabricate make it (fabricate.hpp).
#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "fabricate/fabricate.hpp"

namespace softevo::fabricate {

void parse_dpi(const std::string& text, Options& options) {
  const auto comma = text.find(',');
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  const bool x_ok = comma != std::string::npos && end == text.c_str() + comma;
  const double y = x_ok ? std::strtod(text.c_str() + comma + 1, &end) : 0.0;
  if (!x_ok || *end != '\0' || end == text.c_str() + comma + 1)
    throw FabricateError("fabricate: --dpi " + text + " is not X,Y (e.g. 600,300)");
  options.dpi_x = x;
  options.dpi_y = y;
}

void parse_split(const std::string& text, Options& options) {
  char* end = nullptr;
  const bool prefixed = text.rfind("z=", 0) == 0;
  const double z = prefixed ? std::strtod(text.c_str() + 2, &end) : 0.0;
  if (!prefixed || end == text.c_str() + 2 || *end != '\0')
    throw FabricateError("fabricate: --split " + text +
                         " is not z=HEIGHT (mm above the body's bottom)");
  options.split_z = z * 1e-3;
}

Provenance provenance_of(const RobotFile& robot) {
  Provenance pv;
  pv.name = robot.name;
  if (robot.evaluation) {
    pv.genome_id = robot.evaluation->id;
    pv.generation = robot.evaluation->generation;
    pv.run = robot.evaluation->run;
    pv.config_hash = robot.evaluation->config_hash;
    pv.fitness = robot.evaluation->fitness;
  }
  for (const auto& m : robot.body.materials) pv.youngs_modulus.push_back(m.youngs_modulus);
  return pv;
}

Written fabricate_robot(const RobotFile& robot, const Provenance& provenance,
                        const Request& request) {
  if (request.output.empty() && request.slices.empty() && request.mold.empty())
    throw FabricateError(
        "fabricate: nothing to write: give -o OUT (.3mf or .stl), --slices DIR "
        "or --mold DIR");
  std::string format = request.format;
  if (format.empty() && !request.output.empty()) {
    format = std::filesystem::path(request.output).extension().string();
    for (char& c : format) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!format.empty()) format.erase(0, 1);
  }
  if (!request.output.empty() && format != "3mf" && format != "stl")
    throw FabricateError("fabricate: -o " + request.output +
                         ": the format is .3mf or .stl (by the extension or --format)");
  if (format == "3mf" && !have_3mf())
    throw FabricateError("fabricate: -o " + request.output +
                         ": this softevo was built without lib3mf (install lib3mf-dev and "
                         "rebuild); .stl works without it");
  if (std::none_of(robot.body.cells.begin(), robot.body.cells.end(), BodyPlan::is_structural))
    throw FabricateError("fabricate: the robot has no voxels: nothing to make");
  const scene::Body body = scene::body_from_plan(robot.body);
  Written w{fabricate(body, provenance, request.options), std::nullopt, {}, 0};
  if (!request.mold.empty()) w.mold = make_mold(w.fabrication);
  // Every target is checked (and the slices' size) before the first file is written.
  std::vector<std::string> targets;
  if (format == "3mf") targets.push_back(request.output);
  if (format == "stl") targets = stl_paths(w.fabrication, request.output);
  if (!request.slices.empty()) {
    for (const auto& p : slice_paths(w.fabrication, request.slices)) targets.push_back(p);
  }
  if (w.mold) {
    for (const auto& p : mold_paths(*w.mold, request.mold)) targets.push_back(p);
  }
  for (const auto& p : targets) check_output_target(p, request.overwrite);
  if (!request.slices.empty()) make_output_directory(request.slices, "--slices");
  if (w.mold) make_output_directory(request.mold, "--mold");
  if (!request.output.empty()) {
    if (format == "3mf") {
      write_3mf(w.fabrication, request.output, request.overwrite);
      w.files.push_back(request.output);
    } else {
      w.files = write_stls(w.fabrication, request.output, request.overwrite);
    }
  }
  if (!request.slices.empty())
    w.slices = write_slices(w.fabrication, request.slices, request.overwrite);
  if (w.mold) {
    for (const auto& p : write_mold(*w.mold, request.mold, request.overwrite)) w.files.push_back(p);
  }
  return w;
}

}  // namespace softevo::fabricate
