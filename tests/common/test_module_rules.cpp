// Architecture rules (ARCHITECTURE.md section 1) that the compiler cannot see: physics/ and evo/
// never include MPI or HDF5, evo/ never includes physics/, physics/ never includes evo/.
// The CMake target links enforce the same rules at link time.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path source_dir() {
  const char* env = std::getenv("SOFTEVO_SOURCE_DIR");
  return env ? fs::path(env) : fs::current_path();
}

struct Violation {
  std::string file;
  int line;
  std::string text;
};

// Every #include in the module's sources whose target matches `forbidden`.
std::vector<Violation> forbidden_includes(const std::string& module, const std::regex& forbidden) {
  std::vector<Violation> found;
  const std::regex include_line(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  for (const auto& entry : fs::recursive_directory_iterator(source_dir() / module)) {
    const auto ext = entry.path().extension();
    if (ext != ".cpp" && ext != ".hpp" && ext != ".h" && ext != ".cc") continue;
    std::ifstream in(entry.path());
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      std::smatch m;
      if (std::regex_search(line, m, include_line) && std::regex_search(m[1].str(), forbidden)) {
        found.push_back({entry.path().string(), number, line});
      }
    }
  }
  return found;
}

std::string describe(const std::vector<Violation>& v) {
  std::string s;
  for (const auto& x : v) s += x.file + ":" + std::to_string(x.line) + ": " + x.text + "\n";
  return s;
}

const std::regex kMpiOrHdf5(R"(^(mpi\.h|mpi|H5Cpp\.h|hdf5\.h|H5[A-Za-z]*\.h|hdf5_hl\.h)$)");

}  // namespace

TEST(ModuleRules, PhysicsIncludesNoMpiHdf5OrEvo) {
  const auto v = forbidden_includes("physics", kMpiOrHdf5);
  EXPECT_TRUE(v.empty()) << describe(v);
  const auto e = forbidden_includes("physics", std::regex(R"(^(evo|worker|master)/)"));
  EXPECT_TRUE(e.empty()) << describe(e);
}

TEST(ModuleRules, EvoIncludesNoMpiHdf5OrPhysics) {
  const auto v = forbidden_includes("evo", kMpiOrHdf5);
  EXPECT_TRUE(v.empty()) << describe(v);
  const auto p = forbidden_includes("evo", std::regex(R"(^(physics|worker|master)/)"));
  EXPECT_TRUE(p.empty()) << describe(p);
}

TEST(ModuleRules, CommonDependsOnNoOtherModule) {
  const auto v = forbidden_includes("common", std::regex(R"(^(physics|evo|worker|master)/)"));
  EXPECT_TRUE(v.empty()) << describe(v);
  const auto m = forbidden_includes("common", kMpiOrHdf5);
  EXPECT_TRUE(m.empty()) << describe(m);
}

TEST(ModuleRules, WorkerEvaluationLogicIsMpiFree) {
  // Only the thin driver worker_loop.* may talk MPI; worker/ never writes HDF5.
  std::vector<Violation> v;
  for (const auto& x : forbidden_includes("worker", kMpiOrHdf5)) {
    if (x.file.find("worker_loop") == std::string::npos) v.push_back(x);
  }
  EXPECT_TRUE(v.empty()) << describe(v);
}

TEST(ModuleRules, DetectorFindsAPlantedViolation) {
  // The scanner must be able to fail: plant a file and check it is reported.
  const fs::path dir = fs::temp_directory_path() / "softevo_rules_probe";
  fs::create_directories(dir / "probe");
  std::ofstream(dir / "probe" / "x.cpp") << "#include <mpi.h>\n#include \"physics/model.hpp\"\n";
  const char* previous = std::getenv("SOFTEVO_SOURCE_DIR");
  const std::string saved = previous ? previous : "";
  setenv("SOFTEVO_SOURCE_DIR", dir.c_str(), 1);
  const auto mpi = forbidden_includes("probe", kMpiOrHdf5);
  const auto phys = forbidden_includes("probe", std::regex(R"(^physics/)"));
  if (previous) {
    setenv("SOFTEVO_SOURCE_DIR", saved.c_str(), 1);
  } else {
    unsetenv("SOFTEVO_SOURCE_DIR");
  }
  fs::remove_all(dir);
  EXPECT_EQ(mpi.size(), 1u);
  EXPECT_EQ(phys.size(), 1u);
}

TEST(ModuleRules, OnlyIoIncludesHdf5AndNothingTheCxxBindings) {
  // io/ is the one room over the HDF5 C API (io/h5.hpp); every other room reads and writes
  // files through io/'s headers, which do not include hdf5.h. The C++ bindings are used nowhere
  // (tests included): clusters often install HDF5 without them.
  const std::regex hdf5_header(R"(^(hdf5\.h|hdf5_hl\.h|H5[A-Za-z]*\.h)$)");
  std::vector<Violation> v;
  for (const auto& entry : fs::directory_iterator(source_dir())) {
    const std::string room = entry.path().filename().string();
    if (!entry.is_directory() || !fs::exists(entry.path() / "CMakeLists.txt")) continue;
    if (room == "io" || room == "tests") continue;
    for (const auto& x : forbidden_includes(room, hdf5_header)) v.push_back(x);
  }
  for (const char* room : {"io", "tests"})
    for (const auto& x : forbidden_includes(room, std::regex(R"(^H5Cpp\.h$)"))) v.push_back(x);
  EXPECT_TRUE(v.empty()) << describe(v);
}
