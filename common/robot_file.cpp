// Strict reader and writer of the robot file `softevo.robot/1` (docs/model.md §10).
//
// Strictness rules: every object is checked for unknown keys; every value is type-checked; the
// controller vector lengths follow from the input count of §4.1 (2 x oscillator_inputs +
// directed + 10 x closed) and the layouts of §4.4. Any problem is a RobotFileError "<file>: key
// '<path>': <problem>". `reference` is never interpreted: it is kept as JSON text (key order
// preserved).
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/config_identity.hpp"
#include "common/input_file.hpp"
#include "common/robot.hpp"

namespace softevo {
namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kFormat = "softevo.robot/1";
constexpr int kDefaultMaterialCount = 10;             // materials 1..10 (docs/model.md §1)
constexpr double kDefaultModulusStep = 10000.0;       // E_k = 10 kPa x k [Pa]
constexpr double kDefaultDensity = 1000.0;            // [kg/m^3]
constexpr int kMaxCellValue = kFirstChamberCell + 9;  // chambers 11..20
// Deepest JSON nesting a robot file may have. A real file nests about 5 levels (genome, its
// genes, their fields); `reference` holds a few more. Re-serialising `reference` with dump() is
// recursive, so an adversarial file with 65k levels would overflow the stack: refuse it on read.
constexpr int kMaxJsonDepth = 64;

// Error context: the file (or source) name and the dotted key path of the current value.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw RobotFileError(source_ + ": key '" + key + "': " + problem);
  }
  [[noreturn]] void fail_top(const std::string& problem) const {
    throw RobotFileError(source_ + ": " + problem);
  }

  static std::string join(const std::string& parent, const std::string& key) {
    return parent.empty() ? key : parent + "." + key;
  }

  static const char* type_name(const Json& j) { return j.type_name(); }

  void expect_object(const Json& j, const std::string& key) const {
    if (!j.is_object()) fail(key, std::string("expected an object, got ") + type_name(j));
  }

  // Unknown keys are errors (§10).
  void check_keys(const Json& obj, const std::string& key,
                  std::initializer_list<const char*> allowed) const {
    for (const auto& item : obj.items()) {
      bool known = false;
      for (const char* a : allowed) known = known || item.key() == a;
      if (!known) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
        fail(join(key, item.key()), "unknown key (allowed here: " + list + ")");
      }
    }
  }

  const Json& require(const Json& obj, const std::string& parent, const char* name) const {
    auto it = obj.find(name);
    if (it == obj.end()) fail(join(parent, name), "missing required key");
    return *it;
  }

  double number(const Json& j, const std::string& key) const {
    if (!j.is_number()) fail(key, std::string("expected a number, got ") + type_name(j));
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(key, "number is not finite");
    return v;
  }

  long long integer(const Json& j, const std::string& key) const {
    if (j.is_number_integer()) return j.get<long long>();
    if (j.is_number_float()) {
      const double v = j.get<double>();
      // In range before the cast: converting a double beyond long long is undefined (a cell
      // of 4.4e68 reached it, found by fuzz_robot_file); -2^63 <= v < 2^63 are exact doubles.
      constexpr double kLimit = 9223372036854775808.0;  // 2^63
      if (std::isfinite(v) && v >= -kLimit && v < kLimit &&
          v == static_cast<double>(static_cast<long long>(v)))
        return static_cast<long long>(v);
    }
    fail(key, std::string("expected an integer, got ") + (j.is_number() ? j.dump() : type_name(j)));
  }

  int int_in(const Json& j, const std::string& key, long long lo, long long hi) const {
    const long long v = integer(j, key);
    if (v < lo || v > hi)
      fail(key, "value " + std::to_string(v) + " out of range [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
    return static_cast<int>(v);
  }

  bool boolean(const Json& j, const std::string& key) const {
    if (!j.is_boolean()) fail(key, std::string("expected true or false, got ") + type_name(j));
    return j.get<bool>();
  }

  std::string string(const Json& j, const std::string& key) const {
    if (!j.is_string()) fail(key, std::string("expected a string, got ") + type_name(j));
    return j.get<std::string>();
  }

  std::vector<double> numbers(const Json& j, const std::string& key, std::size_t length,
                              const std::string& why) const {
    if (!j.is_array()) fail(key, std::string("expected an array of numbers, got ") + type_name(j));
    if (j.size() != length)
      fail(key, "expected " + std::to_string(length) + " numbers (" + why + "), got " +
                    std::to_string(j.size()));
    std::vector<double> out;
    out.reserve(length);
    for (std::size_t i = 0; i < j.size(); ++i)
      out.push_back(number(j[i], key + "[" + std::to_string(i) + "]"));
    return out;
  }

  std::array<int, 3> lattice(const Json& j, const std::string& key) const {
    if (!j.is_array() || j.size() != 3) fail(key, "expected an array of 3 positive integers");
    std::array<int, 3> out{};
    for (std::size_t i = 0; i < 3; ++i)
      out[i] = int_in(j[i], key + "[" + std::to_string(i) + "]", 1, 1000);
    return out;
  }

 private:
  std::string source_;
};

// The dotted key path ("controller.weights_in[3]") of the value the parser reads next, followed
// through its callback events, so that an error the parser raises mid-value can name the key.
class KeyPath {
 public:
  void follow(Json::parse_event_t event, const Json& parsed) {
    switch (event) {
      case Json::parse_event_t::object_start:
      case Json::parse_event_t::array_start:
        begin_value();
        parts_.push_back({event == Json::parse_event_t::array_start, -1, ""});
        break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        if (!parts_.empty()) parts_.pop_back();
        break;
      case Json::parse_event_t::key:
        if (!parts_.empty()) parts_.back().key = parsed.get<std::string>();
        break;
      case Json::parse_event_t::value:
        begin_value();
        break;
    }
  }
  // The key of the value being read (an array element: its index; the next one, mid-value).
  std::string text() const {
    std::string out;
    for (std::size_t i = 0; i < parts_.size(); ++i) {
      const Part& p = parts_[i];
      if (p.array) {
        out += "[" + std::to_string(p.index + (i + 1 == parts_.size() ? 1 : 0)) + "]";
      } else if (!p.key.empty()) {
        out += (out.empty() ? "" : ".") + p.key;
      }
    }
    return out;
  }

 private:
  struct Part {
    bool array = false;
    long long index = -1;  // array: index of the last element begun
    std::string key;       // object: the last key read
  };
  void begin_value() {
    if (!parts_.empty() && parts_.back().array) ++parts_.back().index;
  }
  std::vector<Part> parts_;
};

// The 8 weight vectors of §4.4 with their lengths for (n_in, hidden, outputs). `freq` is
// handled separately (a scalar "frequency" in the controller, a 1-vector in the step sizes).
struct VectorSlot {
  const char* name;
  std::vector<double> ControllerVectors::*member;
  std::size_t length;
  std::string why;
};

std::vector<VectorSlot> vector_slots(int n_in, int hidden, int outputs) {
  const auto h = static_cast<std::size_t>(hidden);
  const auto o = static_cast<std::size_t>(outputs);
  const auto n = static_cast<std::size_t>(n_in);
  const std::string hs = std::to_string(hidden), os = std::to_string(outputs),
                    ns = std::to_string(n_in);
  return {
      {"weights_hidden", &ControllerVectors::weights_hidden, n * h,
       "inputs " + ns + " x hidden " + hs},
      {"bias_hidden", &ControllerVectors::bias_hidden, h, "hidden " + hs},
      {"weights_out", &ControllerVectors::weights_out, h * o, "hidden " + hs + " x outputs " + os},
      {"bias_out", &ControllerVectors::bias_out, o, "outputs " + os},
      {"weights_recurrent", &ControllerVectors::weights_recurrent, h * h,
       "hidden " + hs + " x hidden " + hs},
      {"weights_recurrent_self", &ControllerVectors::weights_recurrent_self, h, "hidden " + hs},
      {"weights_context", &ControllerVectors::weights_context, h, "hidden " + hs},
      {"bias_context", &ControllerVectors::bias_context, h, "hidden " + hs},
  };
}

void read_vectors(const Reader& r, const Json& obj, const std::string& key, int n_in, int hidden,
                  int outputs, ControllerVectors& out) {
  for (const auto& slot : vector_slots(n_in, hidden, outputs)) {
    const std::string k = Reader::join(key, slot.name);
    out.*(slot.member) = r.numbers(r.require(obj, key, slot.name), k, slot.length, slot.why);
  }
}

ControllerSpec read_controller(const Reader& r, const Json& j) {
  const std::string key = "controller";
  r.expect_object(j, key);
  r.check_keys(j, key,
               {"kind", "control", "directed", "oscillator_inputs", "hidden", "outputs",
                "frequency", "weights_hidden", "bias_hidden", "weights_out", "bias_out",
                "weights_recurrent", "weights_recurrent_self", "weights_context", "bias_context"});
  ControllerSpec c;
  if (auto it = j.find("kind"); it != j.end()) {
    c.kind = r.string(*it, "controller.kind");
    if (c.kind != "elman") r.fail("controller.kind", "unknown kind '" + c.kind + "' (only elman)");
  }
  const std::string control = r.string(r.require(j, key, "control"), "controller.control");
  if (control != "open" && control != "closed")
    r.fail("controller.control", "expected \"open\" or \"closed\", got \"" + control + "\"");
  c.closed_loop = control == "closed";
  c.directed = r.boolean(r.require(j, key, "directed"), "controller.directed");
  if (auto it = j.find("oscillator_inputs"); it != j.end())
    c.oscillator_inputs = r.boolean(*it, "controller.oscillator_inputs");
  if (auto it = j.find("hidden"); it != j.end())
    c.hidden = r.int_in(*it, "controller.hidden", 1, 1000);
  if (auto it = j.find("outputs"); it != j.end())
    c.outputs = r.int_in(*it, "controller.outputs", 1, 1000);
  const double f = r.number(r.require(j, key, "frequency"), "controller.frequency");
  if (!(f > 0.0)) r.fail("controller.frequency", "must be > 0 Hz");
  c.vectors.freq = {f};
  read_vectors(r, j, key, c.input_count(), c.hidden, c.outputs, c.vectors);
  return c;
}

const std::set<std::string>& activation_names() {
  static const std::set<std::string> names = {"sigmoid", "sin",     "abs",   "square",
                                              "exp",     "clamped", "gauss", "tanh"};
  return names;
}

RobotGenomeRecord read_genome(const Reader& r, const Json& j, const ControllerSpec& controller) {
  const std::string key = "genome";
  r.expect_object(j, key);
  r.check_keys(j, key, {"cppn", "controller_step_sizes", "body"});
  RobotGenomeRecord g;
  if (auto it = j.find("cppn"); it != j.end()) {
    const std::string ck = "genome.cppn";
    r.expect_object(*it, ck);
    r.check_keys(*it, ck, {"nodes", "connections"});
    const Json& nodes = r.require(*it, ck, "nodes");
    if (!nodes.is_array()) r.fail(ck + ".nodes", "expected an array of node objects");
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const std::string nk = ck + ".nodes[" + std::to_string(i) + "]";
      const Json& n = nodes[i];
      r.expect_object(n, nk);
      r.check_keys(n, nk, {"key", "bias", "response", "activation", "aggregation"});
      CppnNodeRecord rec;
      rec.key = r.int_in(r.require(n, nk, "key"), nk + ".key", 0, 1 << 30);
      rec.bias = r.number(r.require(n, nk, "bias"), nk + ".bias");
      if (auto f = n.find("response"); f != n.end()) rec.response = r.number(*f, nk + ".response");
      rec.activation = r.string(r.require(n, nk, "activation"), nk + ".activation");
      if (!activation_names().count(rec.activation))
        r.fail(nk + ".activation", "unknown activation '" + rec.activation + "'");
      if (auto f = n.find("aggregation"); f != n.end()) {
        rec.aggregation = r.string(*f, nk + ".aggregation");
        if (rec.aggregation != "sum")
          r.fail(nk + ".aggregation", "unknown aggregation '" + rec.aggregation + "' (only sum)");
      }
      g.nodes.push_back(rec);
    }
    const Json& conns = r.require(*it, ck, "connections");
    if (!conns.is_array()) r.fail(ck + ".connections", "expected an array of connection objects");
    for (std::size_t i = 0; i < conns.size(); ++i) {
      const std::string nk = ck + ".connections[" + std::to_string(i) + "]";
      const Json& c = conns[i];
      r.expect_object(c, nk);
      r.check_keys(c, nk, {"in", "out", "weight", "enabled"});
      CppnConnectionRecord rec;
      rec.in = r.int_in(r.require(c, nk, "in"), nk + ".in", -4, 1 << 30);
      rec.out = r.int_in(r.require(c, nk, "out"), nk + ".out", 0, 1 << 30);
      rec.weight = r.number(r.require(c, nk, "weight"), nk + ".weight");
      if (auto f = c.find("enabled"); f != c.end()) rec.enabled = r.boolean(*f, nk + ".enabled");
      g.connections.push_back(rec);
    }
  }
  if (auto it = j.find("controller_step_sizes"); it != j.end()) {
    const std::string sk = "genome.controller_step_sizes";
    r.expect_object(*it, sk);
    r.check_keys(*it, sk,
                 {"weights_hidden", "bias_hidden", "weights_out", "bias_out", "weights_recurrent",
                  "weights_recurrent_self", "weights_context", "bias_context", "freq"});
    read_vectors(r, *it, sk, controller.input_count(), controller.hidden, controller.outputs,
                 g.controller_step_sizes);
    g.controller_step_sizes.freq =
        r.numbers(r.require(*it, sk, "freq"), sk + ".freq", 1, "one frequency gene");
  }
  if (auto it = j.find("body"); it != j.end()) {
    const std::string bk = "genome.body";
    r.expect_object(*it, bk);
    r.check_keys(*it, bk, {"lattice", "distance_input"});
    if (auto f = it->find("lattice"); f != it->end()) {
      const auto l = r.lattice(*f, bk + ".lattice");
      g.body_lattice = {l[0], l[1], l[2]};
    }
    if (auto f = it->find("distance_input"); f != it->end()) {
      const std::string name = r.string(*f, bk + ".distance_input");
      const auto distance_input = choice_from_string<DistanceInput>(name);
      if (!distance_input)
        r.fail(bk + ".distance_input", "expected \"pneuvox\" or \"center\", got \"" + name + "\"");
      g.distance_input = *distance_input;
    }
  }
  return g;
}

RobotEvaluation read_evaluation(const Reader& r, const Json& j) {
  const std::string key = "evaluation";
  r.expect_object(j, key);
  r.check_keys(
      j, key,
      {"config", "config_hash", "experiment_hash", "run", "generation", "id", "fitness", "status"});
  RobotEvaluation e;
  e.config = r.string(r.require(j, key, "config"), "evaluation.config");
  e.config_hash = r.string(r.require(j, key, "config_hash"), "evaluation.config_hash");
  // The hashes say the text is the run's: an edited config would silently evaluate another
  // experiment under the run's name.
  const std::string text_hex = hash_hex(text_hash(e.config));
  if (e.config_hash != text_hex)
    r.fail("evaluation.config_hash", "is " + e.config_hash + " but evaluation.config hashes to " +
                                         text_hex + " (the config text was edited after export)");
  const std::string experiment_hex = hash_hex(experiment_hash_of_text(e.config));
  e.experiment_hash = experiment_hex;
  if (auto it = j.find("experiment_hash"); it != j.end()) {
    const std::string given = r.string(*it, "evaluation.experiment_hash");
    if (given != experiment_hex)
      r.fail("evaluation.experiment_hash",
             "is " + given + " but evaluation.config gives " + experiment_hex);
  }
  if (auto it = j.find("run"); it != j.end()) e.run = r.string(*it, "evaluation.run");
  if (auto it = j.find("generation"); it != j.end())
    e.generation = r.integer(*it, "evaluation.generation");
  if (auto it = j.find("id"); it != j.end()) e.id = r.integer(*it, "evaluation.id");
  if (auto it = j.find("fitness"); it != j.end()) e.fitness = r.number(*it, "evaluation.fitness");
  if (auto it = j.find("status"); it != j.end()) e.status = r.string(*it, "evaluation.status");
  return e;
}

std::vector<StructuralMaterial> default_materials() {
  std::vector<StructuralMaterial> m(kDefaultMaterialCount);
  for (int k = 1; k <= kDefaultMaterialCount; ++k)
    m[k - 1] = {kDefaultModulusStep * k, kDefaultDensity};
  return m;
}

void read_body(const Reader& r, const Json& root, BodyPlan& body) {
  body.voxel_size = r.number(r.require(root, "", "voxel_size"), "voxel_size");
  if (!(body.voxel_size > 0.0)) r.fail("voxel_size", "must be > 0 m");
  body.lattice = r.lattice(r.require(root, "", "lattice"), "lattice");
  const std::size_t count = static_cast<std::size_t>(body.lattice[0]) * body.lattice[1] *
                            static_cast<std::size_t>(body.lattice[2]);
  const Json& cells = r.require(root, "", "cells");
  if (!cells.is_array()) r.fail("cells", "expected an array of integers");
  if (cells.size() != count)
    r.fail("cells", "expected " + std::to_string(count) + " values (lattice " +
                        std::to_string(body.lattice[0]) + "x" + std::to_string(body.lattice[1]) +
                        "x" + std::to_string(body.lattice[2]) + "), got " +
                        std::to_string(cells.size()));
  body.cells.resize(count);
  std::vector<bool> chamber_seen(kMaxCellValue - kFirstChamberCell + 1, false);
  for (std::size_t i = 0; i < count; ++i) {
    const int v = r.int_in(cells[i], "cells[" + std::to_string(i) + "]", 0, kMaxCellValue);
    body.cells[i] = v;
    if (v >= kFirstChamberCell) chamber_seen[v - kFirstChamberCell] = true;
  }
  // Chamber ids are dense from 11 (chamber q owns controller outputs 2q, 2q+1, §6.6).
  const int chambers = body.chamber_count();
  for (int q = 0; q < chambers; ++q)
    if (!chamber_seen[q])
      r.fail("cells", "chamber " + std::to_string(q) + " (cell value " +
                          std::to_string(kFirstChamberCell + q) +
                          ") is missing but a higher chamber id exists; ids must be dense from 11");

  body.materials = default_materials();
  if (auto it = root.find("materials"); it != root.end()) {
    r.expect_object(*it, "materials");
    for (const auto& item : it->items()) {
      const std::string mk = "materials." + item.key();
      int k = 0;
      try {
        std::size_t used = 0;
        k = std::stoi(item.key(), &used);
        if (used != item.key().size()) k = 0;
      } catch (const std::exception&) {
        k = 0;
      }
      if (k < 1 || k >= kFirstChamberCell)
        r.fail(mk, "material keys are structural cell values \"1\"..\"10\"");
      r.expect_object(item.value(), mk);
      r.check_keys(item.value(), mk, {"youngs_modulus", "density"});
      StructuralMaterial& m = body.materials[k - 1];
      if (auto f = item.value().find("youngs_modulus"); f != item.value().end()) {
        m.youngs_modulus = r.number(*f, mk + ".youngs_modulus");
        if (!(m.youngs_modulus > 0.0)) r.fail(mk + ".youngs_modulus", "must be > 0 Pa");
      }
      if (auto f = item.value().find("density"); f != item.value().end()) {
        m.density = r.number(*f, mk + ".density");
        if (!(m.density > 0.0)) r.fail(mk + ".density", "must be > 0 kg/m^3");
      }
    }
  }
}

Json vectors_to_json(const ControllerVectors& v, int n_in, int hidden, int outputs,
                     bool with_freq) {
  Json out = Json::object();
  for (const auto& slot : vector_slots(n_in, hidden, outputs)) out[slot.name] = v.*(slot.member);
  if (with_freq) out["freq"] = v.freq;
  return out;
}

}  // namespace

RobotFile parse_robot_json(const std::string& json_text, const std::string& source_name) {
  const Reader r(source_name);
  Json root;
  bool too_deep = false;
  KeyPath path;
  const Json::parser_callback_t refuse_deep_nesting =
      [&too_deep, &path](int depth, Json::parse_event_t event, Json& parsed) {
        path.follow(event, parsed);
        // Returning false discards the value, so the parser neither recurses nor allocates further.
        if (depth > kMaxJsonDepth) too_deep = true;
        return !too_deep;
      };
  try {
    root = Json::parse(json_text, refuse_deep_nesting);
  } catch (const Json::parse_error& e) {
    r.fail_top(std::string("not valid JSON: ") + e.what());
  } catch (const Json::out_of_range& e) {
    // A number beyond the range of a double (1e999): the parser's message names neither the
    // file nor the key.
    const std::string problem = std::string("number out of range (beyond a double): ") + e.what();
    if (path.text().empty()) r.fail_top(problem);
    r.fail(path.text(), problem);
  }
  if (too_deep)
    r.fail_top("JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
               " levels (a robot file needs fewer than 10)");
  if (!root.is_object()) r.fail_top("the robot file must be a JSON object");
  r.check_keys(root, "",
               {"format", "name", "voxel_size", "lattice", "cells", "materials", "controller",
                "genome", "evaluation", "reference"});
  const std::string format = r.string(r.require(root, "", "format"), "format");
  if (format != kFormat)
    r.fail("format", "expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");

  RobotFile robot;
  if (auto it = root.find("name"); it != root.end()) robot.name = r.string(*it, "name");
  read_body(r, root, robot.body);
  robot.controller = read_controller(r, r.require(root, "", "controller"));
  const int chambers = robot.body.chamber_count();
  if (2 * chambers > robot.controller.outputs)
    r.fail("controller.outputs", std::to_string(robot.controller.outputs) +
                                     " outputs cannot drive " + std::to_string(chambers) +
                                     " chambers (2 valves each, §4.5)");
  if (auto it = root.find("genome"); it != root.end())
    robot.genome = read_genome(r, *it, robot.controller);
  if (auto it = root.find("evaluation"); it != root.end())
    robot.evaluation = read_evaluation(r, *it);
  if (auto it = root.find("reference"); it != root.end()) {
    r.expect_object(*it, "reference");
    robot.reference_json = it->dump();
  }
  return robot;
}

RobotFile read_robot_file(const std::string& path) {
  // A file of another kind: say what it is and what takes it, not a JSON parse error at byte 1.
  switch (file_magic(path)) {
    case FileMagic::hdf5:
      throw RobotFileError(path +
                           ": not a robot file: it is an HDF5 file (a run archive or a "
                           "trace); `softevo export RUN.h5 -o robot.json` writes a robot of a "
                           "run archive, and `softevo render`, `view` and `replay` take the "
                           "archive itself");
    case FileMagic::png:
      throw RobotFileError(path + ": not a robot file: it is a PNG image");
    case FileMagic::zip:
    case FileMagic::gzip:
      throw RobotFileError(path + ": not a robot file: it is a compressed file");
    default:
      break;
  }
  std::string text;
  try {
    text = read_input_file(path, InputLimits::robot_file_bytes, "robot file");
  } catch (const InputFileError& e) {
    throw RobotFileError(e.what());
  }
  return parse_robot_json(text, path);
}

std::string robot_to_json(const RobotFile& robot) {
  Json root = Json::object();
  root["format"] = kFormat;
  if (!robot.name.empty()) root["name"] = robot.name;
  const BodyPlan& b = robot.body;
  root["voxel_size"] = b.voxel_size;
  root["lattice"] = {b.lattice[0], b.lattice[1], b.lattice[2]};
  root["cells"] = b.cells;
  Json materials = Json::object();
  for (std::size_t k = 0; k < b.materials.size(); ++k)
    materials[std::to_string(k + 1)] = {{"youngs_modulus", b.materials[k].youngs_modulus},
                                        {"density", b.materials[k].density}};
  root["materials"] = materials;

  const ControllerSpec& c = robot.controller;
  Json ctrl = Json::object();
  ctrl["kind"] = c.kind;
  ctrl["control"] = c.closed_loop ? "closed" : "open";
  ctrl["directed"] = c.directed;
  // Written only when false, so that every file of a controller with oscillator inputs keeps
  // its bytes.
  if (!c.oscillator_inputs) ctrl["oscillator_inputs"] = false;
  ctrl["hidden"] = c.hidden;
  ctrl["outputs"] = c.outputs;
  ctrl["frequency"] = c.frequency();
  const Json vectors = vectors_to_json(c.vectors, c.input_count(), c.hidden, c.outputs, false);
  for (const auto& item : vectors.items()) ctrl[item.key()] = item.value();
  root["controller"] = ctrl;

  if (robot.genome) {
    const RobotGenomeRecord& g = *robot.genome;
    Json nodes = Json::array();
    for (const auto& n : g.nodes)
      nodes.push_back({{"key", n.key},
                       {"bias", n.bias},
                       {"response", n.response},
                       {"activation", n.activation},
                       {"aggregation", n.aggregation}});
    Json conns = Json::array();
    for (const auto& e : g.connections)
      conns.push_back({{"in", e.in}, {"out", e.out}, {"weight", e.weight}, {"enabled", e.enabled}});
    Json genome = Json::object();
    genome["cppn"] = {{"nodes", nodes}, {"connections", conns}};
    if (!g.controller_step_sizes.freq.empty())
      genome["controller_step_sizes"] =
          vectors_to_json(g.controller_step_sizes, c.input_count(), c.hidden, c.outputs, true);
    genome["body"] = {{"lattice", g.body_lattice}, {"distance_input", to_string(g.distance_input)}};
    root["genome"] = genome;
  }
  if (robot.evaluation) {
    const RobotEvaluation& e = *robot.evaluation;
    Json ev = Json::object();
    ev["config"] = e.config;
    ev["config_hash"] = hash_hex(text_hash(e.config));
    ev["experiment_hash"] = hash_hex(experiment_hash_of_text(e.config));
    if (!e.run.empty()) ev["run"] = e.run;
    if (e.generation) ev["generation"] = *e.generation;
    if (e.id) ev["id"] = *e.id;
    if (e.fitness) ev["fitness"] = *e.fitness;
    if (!e.status.empty()) ev["status"] = e.status;
    root["evaluation"] = ev;
  }
  if (!robot.reference_json.empty()) {
    try {
      root["reference"] = Json::parse(robot.reference_json);
    } catch (const Json::parse_error& e) {
      throw RobotFileError(std::string("robot '") + robot.name +
                           "': reference_json is not valid JSON: " + e.what());
    }
  }
  // nlohmann writes doubles in the shortest form that reads back to the same bits.
  return root.dump(1) + "\n";
}

void write_robot_file(const RobotFile& robot, const std::string& path, Overwrite overwrite) {
  write_file_atomically(path, robot_to_json(robot), overwrite);
}

}  // namespace softevo
