// Robot file `softevo.robot/1` (docs/model.md §10): strict reader, writer round trip, and the
// thesis champions of ../shared/reference/bestbots parse.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "common/robot.hpp"

namespace fs = std::filesystem;
using softevo::RobotFile;
using softevo::RobotFileError;

namespace {

fs::path shared_dir() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  return (env ? fs::path(env) : fs::current_path()) / ".." / "shared";
}

// A minimal valid open-loop robot: 3x1x3 lattice, one chamber cell in the middle.
nlohmann::ordered_json minimal_robot() {
  nlohmann::ordered_json j;
  j["format"] = "softevo.robot/1";
  j["name"] = "tiny";
  j["voxel_size"] = 0.01;
  j["lattice"] = {3, 1, 3};
  j["cells"] = {10, 10, 10, 10, 11, 10, 10, 10, 10};
  nlohmann::ordered_json c;
  c["kind"] = "elman";
  c["control"] = "open";
  c["directed"] = false;
  c["hidden"] = 4;
  c["outputs"] = 20;
  c["frequency"] = 3.2;
  c["weights_hidden"] = std::vector<double>(8, 0.25);
  c["bias_hidden"] = std::vector<double>(4, 0.1);
  c["weights_out"] = std::vector<double>(80, -0.5);
  c["bias_out"] = std::vector<double>(20, 0.3);
  c["weights_recurrent"] = std::vector<double>(16, 0.01);
  c["weights_recurrent_self"] = std::vector<double>(4, 0.2);
  c["weights_context"] = std::vector<double>(4, 0.3);
  c["bias_context"] = std::vector<double>(4, 0.4);
  j["controller"] = c;
  return j;
}

std::string error_of(const nlohmann::ordered_json& j) {
  try {
    softevo::parse_robot_json(j.dump(), "robot.json");
  } catch (const RobotFileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RobotFile, MinimalRobotParsesWithDefaults) {
  const RobotFile r = softevo::parse_robot_json(minimal_robot().dump(), "robot.json");
  EXPECT_EQ(r.name, "tiny");
  EXPECT_EQ(r.body.lattice, (std::array<int, 3>{3, 1, 3}));
  EXPECT_EQ(r.body.chamber_count(), 1);
  ASSERT_EQ(r.body.materials.size(), 10u);
  EXPECT_DOUBLE_EQ(r.body.materials[0].youngs_modulus, 1.0e4);  // E_k = 10 kPa x k
  EXPECT_DOUBLE_EQ(r.body.materials[9].youngs_modulus, 1.0e5);
  EXPECT_DOUBLE_EQ(r.body.materials[4].density, 1000.0);
  EXPECT_FALSE(r.controller.closed_loop);
  EXPECT_EQ(r.controller.input_count(), 2);
  EXPECT_DOUBLE_EQ(r.controller.frequency(), 3.2);
  EXPECT_FALSE(r.genome.has_value());
  EXPECT_TRUE(r.reference_json.empty());
}

TEST(RobotFile, RoundTripIsExactAndKeepsReference) {
  auto j = minimal_robot();
  j["controller"]["weights_out"][3] = 0.1 + 0.2;  // needs all 17 digits
  j["materials"] = {{"3", {{"youngs_modulus", 12345.678901234567}, {"density", 999.5}}}};
  j["reference"] = {{"zeta", 1}, {"alpha", {1.5, "x"}}, {"fitness", 69.6804}};
  const RobotFile r = softevo::parse_robot_json(j.dump(), "robot.json");
  EXPECT_EQ(r.controller.vectors.weights_out[3], 0.1 + 0.2);
  EXPECT_EQ(r.body.materials[2].youngs_modulus, 12345.678901234567);
  EXPECT_EQ(r.body.materials[2].density, 999.5);
  // key order of the free-form reference object is preserved
  EXPECT_LT(r.reference_json.find("zeta"), r.reference_json.find("alpha"));

  const fs::path path = fs::temp_directory_path() / "softevo_test_robot_roundtrip.json";
  softevo::write_robot_file(r, path.string());
  const RobotFile back = softevo::read_robot_file(path.string());
  fs::remove(path);
  EXPECT_EQ(back.controller.vectors.weights_out, r.controller.vectors.weights_out);
  EXPECT_EQ(back.body.cells, r.body.cells);
  EXPECT_EQ(back.body.materials[2].youngs_modulus, r.body.materials[2].youngs_modulus);
  EXPECT_EQ(back.reference_json, r.reference_json);
  EXPECT_EQ(softevo::robot_to_json(back), softevo::robot_to_json(r));
}

// controller.oscillator_inputs = false (§4.1, §10): vectors sized without sin/cos, written only
// when false, so a file with oscillator inputs keeps its bytes.
TEST(RobotFile, ControllerWithoutOscillatorInputsRoundTrips) {
  auto j = minimal_robot();
  j["controller"]["control"] = "closed";
  j["controller"]["oscillator_inputs"] = false;
  j["controller"]["weights_hidden"] = std::vector<double>(40, 0.25);  // 10 sensors x 4
  const RobotFile r = softevo::parse_robot_json(j.dump(), "robot.json");
  EXPECT_FALSE(r.controller.oscillator_inputs);
  EXPECT_EQ(r.controller.input_count(), 10);
  const std::string text = softevo::robot_to_json(r);
  EXPECT_NE(text.find("\"oscillator_inputs\": false"), std::string::npos) << text;
  EXPECT_EQ(softevo::robot_to_json(softevo::parse_robot_json(text, "again")), text);
  const RobotFile with = softevo::parse_robot_json(minimal_robot().dump(), "with.json");
  EXPECT_TRUE(with.controller.oscillator_inputs);
  EXPECT_EQ(softevo::robot_to_json(with).find("oscillator_inputs"), std::string::npos);

  j["controller"]["weights_hidden"] = std::vector<double>(48, 0.25);  // sized as with sin/cos
  EXPECT_THROW(softevo::parse_robot_json(j.dump(), "robot.json"), RobotFileError);
  j["controller"]["oscillator_inputs"] = "no";
  try {
    softevo::parse_robot_json(j.dump(), "robot.json");
    FAIL();
  } catch (const RobotFileError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.oscillator_inputs"), std::string::npos)
        << e.what();
  }
}

TEST(RobotFile, ErrorsNameTheKey) {
  struct Case {
    std::string what;
    nlohmann::ordered_json robot;
    std::string expect;  // substring of the message
  };
  std::vector<Case> cases;
  auto add = [&](std::string what, auto mutate, std::string expect) {
    auto j = minimal_robot();
    mutate(j);
    cases.push_back({std::move(what), j, std::move(expect)});
  };
  add(
      "unknown top key", [](auto& j) { j["colour"] = 1; }, "key 'colour': unknown key");
  add(
      "unknown controller key", [](auto& j) { j["controller"]["gain"] = 1; },
      "key 'controller.gain': unknown key");
  add(
      "wrong format", [](auto& j) { j["format"] = "softevo.robot/2"; }, "key 'format'");
  add(
      "missing cells", [](auto& j) { j.erase("cells"); }, "key 'cells': missing required key");
  add(
      "cells length", [](auto& j) { j["cells"].erase(0); }, "key 'cells': expected 9 values");
  add(
      "cell type", [](auto& j) { j["cells"][2] = "x"; }, "key 'cells[2]': expected an integer");
  add(
      "cell range", [](auto& j) { j["cells"][2] = 21; }, "key 'cells[2]': value 21 out of range");
  // Integral doubles beyond long long (fuzz_robot_file: converting them was undefined, which
  // the sanitizer build stops at), at both ends and just past 2^63.
  add(
      "cell beyond long long", [](auto& j) { j["cells"][4] = 4.4444e68; },
      "key 'cells[4]': expected an integer, got 4.4444e+68");
  add(
      "cell below long long", [](auto& j) { j["cells"][4] = -1e19; },
      "key 'cells[4]': expected an integer, got -1e+19");
  add(
      "cell at 2^63", [](auto& j) { j["cells"][4] = 9223372036854775808.0; },
      "key 'cells[4]': expected an integer, got 9.223372036854776e+18");
  add(
      "chamber ids dense", [](auto& j) { j["cells"][4] = 12; }, "ids must be dense from 11");
  add(
      "weights length", [](auto& j) { j["controller"]["weights_hidden"].erase(0); },
      "key 'controller.weights_hidden': expected 8 numbers (inputs 2 x hidden 4), got 7");
  add(
      "closed loop needs 12 inputs", [](auto& j) { j["controller"]["control"] = "closed"; },
      "key 'controller.weights_hidden': expected 48 numbers");
  add(
      "directed needs 3 inputs", [](auto& j) { j["controller"]["directed"] = true; },
      "expected 12 numbers (inputs 3 x hidden 4)");
  add(
      "bool type", [](auto& j) { j["controller"]["directed"] = 1; },
      "key 'controller.directed': expected true or false");
  add(
      "control value", [](auto& j) { j["controller"]["control"] = "half"; },
      "key 'controller.control'");
  add(
      "number type", [](auto& j) { j["controller"]["bias_out"][5] = "0.1"; },
      "key 'controller.bias_out[5]': expected a number");
  add(
      "frequency", [](auto& j) { j["controller"].erase("frequency"); },
      "key 'controller.frequency': missing required key");
  add(
      "material key",
      [](auto& j) {
        j["materials"] = {{"12", {{"density", 1.0}}}};
      },
      "key 'materials.12'");
  add(
      "material field",
      [](auto& j) {
        j["materials"] = {{"2", {{"stiffness", 1.0}}}};
      },
      "key 'materials.2.stiffness': unknown key");
  add(
      "reference type", [](auto& j) { j["reference"] = 3; }, "key 'reference'");
  add(
      "genome activation",
      [](auto& j) {
        nlohmann::ordered_json node = {{"key", 0}, {"bias", 0.0}, {"activation", "relu"}};
        nlohmann::ordered_json cppn;
        cppn["nodes"] = nlohmann::ordered_json::array({node});
        cppn["connections"] = nlohmann::ordered_json::array();
        j["genome"]["cppn"] = cppn;
      },
      "key 'genome.cppn.nodes[0].activation': unknown activation 'relu'");
  add(
      "step sizes length",
      [](auto& j) {
        j["genome"] = {{"controller_step_sizes", j["controller"]}};
      },
      "key 'genome.controller_step_sizes.kind': unknown key");
  for (const auto& c : cases) {
    const std::string msg = error_of(c.robot);
    EXPECT_NE(msg.find("robot.json: "), std::string::npos) << c.what << ": " << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.what << ": got '" << msg << "'";
  }
}

TEST(RobotFile, NotJsonAndMissingFileAreErrors) {
  EXPECT_THROW(softevo::parse_robot_json("{\"format\": ", "x.json"), RobotFileError);
  EXPECT_THROW(softevo::parse_robot_json("[1, 2]", "x.json"), RobotFileError);
  EXPECT_THROW(softevo::read_robot_file("/nonexistent/robot.json"), RobotFileError);
}

// A number beyond a double (1e999) used to escape as the parser's bare "number overflow
// parsing '1e999'", naming neither the file nor the key.
TEST(RobotFile, NumberOverflowNamesTheFileAndTheKey) {
  const std::string text = minimal_robot().dump();
  auto error_with = [&text](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
    try {
      softevo::parse_robot_json(t, "big.json");
    } catch (const RobotFileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const struct {
    const char *from, *to, *key;
  } cases[] = {
      {"\"voxel_size\":0.01", "\"voxel_size\":1e999", "voxel_size"},
      {"\"frequency\":3.2", "\"frequency\":-1e400", "controller.frequency"},
      {"\"bias_hidden\":[0.1,0.1", "\"bias_hidden\":[0.1,1e999", "controller.bias_hidden[1]"},
      {"\"cells\":[10", "\"cells\":[1e999", "cells[0]"},
  };
  for (const auto& c : cases) {
    const std::string expect =
        std::string("big.json: key '") + c.key + "': number out of range (beyond a double)";
    const std::string error = error_with(c.from, c.to);
    EXPECT_EQ(error.rfind(expect, 0), 0u) << error;
  }
}

TEST(RobotFile, DeepNestingIsRefusedNotACrash) {
  // 65k levels inside `reference` once crashed the re-serialisation (a recursive dump()).
  for (const int levels : {65536, 70}) {
    nlohmann::ordered_json j = minimal_robot();
    std::string text = j.dump();
    text.pop_back();  // drop the closing brace and append a deeply nested reference
    text += ",\"reference\": {\"x\": " + std::string(levels, '[') + std::string(levels, ']') + "}}";
    try {
      softevo::parse_robot_json(text, "deep.json");
      ADD_FAILURE() << levels << " levels were accepted";
    } catch (const RobotFileError& e) {
      EXPECT_NE(std::string(e.what()).find("deep.json"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("nested deeper than 64"), std::string::npos) << e.what();
    }
  }
  // Moderate nesting in `reference` is kept verbatim.
  nlohmann::ordered_json j = minimal_robot();
  std::string text = j.dump();
  text.pop_back();
  text += ",\"reference\": {\"x\": " + std::string(20, '[') + std::string(20, ']') + "}}";
  EXPECT_NE(softevo::parse_robot_json(text, "ok.json").reference_json.find("[[[["),
            std::string::npos);
}

TEST(RobotFile, ThesisChampionsParseAndRoundTrip) {
  const fs::path dir = shared_dir() / "reference" / "bestbots";
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared/reference/bestbots not found (" << dir << ")";
  int count = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".json") continue;
    const RobotFile r = softevo::read_robot_file(e.path().string());
    ++count;
    EXPECT_GE(r.body.chamber_count(), 1) << e.path();
    EXPECT_TRUE(r.genome.has_value()) << e.path();
    EXPECT_FALSE(r.reference_json.empty()) << e.path();
    const std::string text = softevo::robot_to_json(r);
    const RobotFile back = softevo::parse_robot_json(text, "roundtrip");
    EXPECT_EQ(softevo::robot_to_json(back), text) << e.path();
    EXPECT_EQ(back.controller.vectors.weights_out, r.controller.vectors.weights_out);
  }
  EXPECT_EQ(count, 40);
}
