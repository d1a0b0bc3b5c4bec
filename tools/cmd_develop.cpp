// `softevo develop ROBOT.json [--json]`: rebuild the body from the file's `genome` (CPPN + body
// settings, §10) with evo::develop_body (docs/model.md §6) and compare it with the
// file's lattice/cells. Exit 0 when equal, 1 with a cell-level diff, 2 on bad input.
#include <array>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "evo/development.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {

namespace {

struct CellDiff {
  std::array<int, 3> at;
  int expected;  // -1 = outside the file's lattice
  int got;       // -1 = outside the developed lattice
};

int cell_or_absent(const BodyPlan& p, int x, int y, int z) {
  if (x >= p.lattice[0] || y >= p.lattice[1] || z >= p.lattice[2]) return -1;
  return p.cell(x, y, z);
}

// Every cell of the union of both lattices (anchored at the origin) whose value differs.
std::vector<CellDiff> diff_cells(const BodyPlan& expected, const BodyPlan& got) {
  std::vector<CellDiff> diffs;
  std::array<int, 3> size{};
  for (int a = 0; a < 3; ++a) size[a] = std::max(expected.lattice[a], got.lattice[a]);
  for (int x = 0; x < size[0]; ++x)
    for (int y = 0; y < size[1]; ++y)
      for (int z = 0; z < size[2]; ++z) {
        const int e = cell_or_absent(expected, x, y, z), g = cell_or_absent(got, x, y, z);
        if (e != g) diffs.push_back(CellDiff{{x, y, z}, e, g});
      }
  return diffs;
}

// One character per cell: '.' empty, '1'..'9' material, '#' material 10, 'a'.. chamber 0..
char cell_char(int v) {
  if (v == kEmptyCell) return '.';
  if (v >= kFirstChamberCell) return static_cast<char>('a' + (v - kFirstChamberCell) % 26);
  if (v == 10) return '#';
  if (v >= 1 && v <= 9) return static_cast<char>('0' + v);
  return '?';
}

std::string lattice_text(const std::array<int, 3>& l) {
  return std::to_string(l[0]) + " x " + std::to_string(l[1]) + " x " + std::to_string(l[2]);
}

struct ChamberInfo {
  int cells = 0;
  std::array<double, 3> centroid{0, 0, 0};  // mean cell index
};

std::vector<ChamberInfo> chamber_info(const BodyPlan& p) {
  std::vector<ChamberInfo> info(static_cast<std::size_t>(p.chamber_count()));
  for (int x = 0; x < p.lattice[0]; ++x)
    for (int y = 0; y < p.lattice[1]; ++y)
      for (int z = 0; z < p.lattice[2]; ++z) {
        const int v = p.cell(x, y, z);
        if (v < kFirstChamberCell) continue;
        auto& c = info[static_cast<std::size_t>(v - kFirstChamberCell)];
        ++c.cells;
        c.centroid[0] += x;
        c.centroid[1] += y;
        c.centroid[2] += z;
      }
  for (auto& c : info)
    for (auto& v : c.centroid) v = c.cells > 0 ? v / c.cells : 0.0;
  return info;
}

void print_text(const std::string& path, const evo::DevelopedBody& body, const BodyPlan& expected,
                const std::vector<CellDiff>& diffs, DistanceInput distance_input) {
  const BodyPlan& p = body.plan;
  std::printf("develop %s (distance_input %s)\n", path.c_str(), to_string(distance_input));
  std::printf("valid %s, actuatable %s\n", body.valid ? "yes" : "no",
              body.actuatable ? "yes" : "no");
  if (body.valid) {
    std::printf("lattice %s\n", lattice_text(p.lattice).c_str());
    const auto chambers = chamber_info(p);
    std::printf("chambers %zu (controller order)\n", chambers.size());
    for (std::size_t q = 0; q < chambers.size(); ++q)
      std::printf("  chamber %zu (cell value %zu): %d cells, centroid (%.2f, %.2f, %.2f)\n", q,
                  q + kFirstChamberCell, chambers[q].cells, chambers[q].centroid[0],
                  chambers[q].centroid[1], chambers[q].centroid[2]);
    std::printf(
        "cells as z-slices (rows y = Y-1 .. 0, columns x = 0 .. X-1); "
        "'.' empty, 1-9 material, '#' material 10, a-j chamber 0-9\n");
    for (int z = p.lattice[2] - 1; z >= 0; --z) {
      std::printf("z = %d\n", z);
      for (int y = p.lattice[1] - 1; y >= 0; --y) {
        std::string row = "  ";
        for (int x = 0; x < p.lattice[0]; ++x) row += cell_char(p.cell(x, y, z));
        std::printf("%s\n", row.c_str());
      }
    }
  }
  if (diffs.empty()) {
    std::printf("MATCH: developed body equals the file's lattice and cells\n");
    return;
  }
  std::printf(
      "MISMATCH: file lattice %s, developed %s; %zu differing cells (x,y,z: expected vs "
      "got; -1 = outside the lattice)\n",
      lattice_text(expected.lattice).c_str(), lattice_text(p.lattice).c_str(), diffs.size());
  for (const auto& d : diffs)
    std::printf("  %d,%d,%d: %d vs %d\n", d.at[0], d.at[1], d.at[2], d.expected, d.got);
}

void print_json(const std::string& path, const evo::DevelopedBody& body,
                const std::vector<CellDiff>& diffs) {
  nlohmann::ordered_json j;
  j["file"] = path;
  j["valid"] = body.valid;
  j["actuatable"] = body.actuatable;
  j["lattice"] = body.plan.lattice;
  j["cells"] = body.plan.cells;
  nlohmann::ordered_json chambers = nlohmann::ordered_json::array();
  const auto info = chamber_info(body.plan);
  for (std::size_t q = 0; q < info.size(); ++q)
    chambers.push_back({{"index", q},
                        {"cell_value", q + kFirstChamberCell},
                        {"cells", info[q].cells},
                        {"centroid", info[q].centroid}});
  j["chambers"] = chambers;
  j["matches"] = diffs.empty();
  nlohmann::ordered_json jd = nlohmann::ordered_json::array();
  for (const auto& d : diffs)
    jd.push_back({{"at", d.at}, {"expected", d.expected}, {"got", d.got}});
  j["differences"] = jd;
  std::printf("%s\n", j.dump(2).c_str());
}

}  // namespace

void register_develop(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "develop",
      "develop the body from a robot file's genome (CPPN, §6) and compare with its cells");
  auto file = std::make_shared<std::string>();
  auto as_json = std::make_shared<bool>(false);
  cmd->add_option("ROBOT", *file, "robot file (softevo.robot/1 JSON) with a genome section")
      ->required();
  cmd->add_flag("--json", *as_json,
                "print a JSON object (lattice, cells, chambers, valid, actuatable, matches)");
  cmd->callback([&exit_code, file, as_json] {
    exit_code = kExitUsage;                          // until the comparison has run
    const RobotFile robot = read_robot_file(*file);  // RobotFileError names file/key: exit 2
    if (!robot.genome)
      throw std::runtime_error(*file + ": no \"genome\" section to develop a body from");
    const RobotGenomeRecord& rec = *robot.genome;
    evo::CppnGenome genome;
    try {
      genome = evo::cppn_from_records(rec.nodes, rec.connections);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(*file + ": genome.cppn: " + e.what());
    }
    BodyConfig config;
    config.lattice.assign(rec.body_lattice.begin(), rec.body_lattice.end());
    config.distance_input = rec.distance_input;
    evo::DevelopedBody body;
    try {
      body = evo::develop_body(genome, config);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(*file + ": genome.body: " + e.what());
    }
    const std::vector<CellDiff> diffs = diff_cells(robot.body, body.plan);
    if (*as_json)
      print_json(*file, body, diffs);
    else
      print_text(*file, body, robot.body, diffs, rec.distance_input);
    exit_code = diffs.empty() ? kExitOk : kExitMismatch;
  });
}

}  // namespace softevo::cli
