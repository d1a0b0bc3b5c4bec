// libFuzzer target: the robot-file reader (common/robot_file) on arbitrary text. Every input
// must either parse or raise RobotFileError; a parsed robot must survive its own round trip.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/robot.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const softevo::RobotFile robot = softevo::parse_robot_json(text, "fuzz.json");
    const std::string again = softevo::robot_to_json(robot);
    const softevo::RobotFile back = softevo::parse_robot_json(again, "fuzz-roundtrip.json");
    if (softevo::robot_to_json(back) != again) __builtin_trap();
  } catch (const softevo::RobotFileError&) {
  }
  return 0;
}
