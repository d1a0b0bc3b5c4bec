// Architecture rules (docs/architecture.md §1) that the compiler cannot see: physics/ and evo/
// never include MPI or HDF5, evo/ never includes physics/, physics/ never includes evo/; only
// mpi/ includes or calls MPI; master/ and worker/ never include each other; motion/ never
// includes render/, scene/ only common/, and fabricate/ only scene/, render/ and common/.
// The CMake target links enforce the same rules at link time.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
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

// Every line of the module's sources for which `matches(line)` holds.
template <class Match>
std::vector<Violation> matching_lines(const std::string& module, const Match& matches) {
  std::vector<Violation> found;
  for (const auto& entry : fs::recursive_directory_iterator(source_dir() / module)) {
    const auto ext = entry.path().extension();
    if (ext != ".cpp" && ext != ".hpp" && ext != ".h" && ext != ".cc") continue;
    std::ifstream in(entry.path());
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      if (matches(line)) found.push_back({entry.path().string(), number, line});
    }
  }
  return found;
}

// Every #include in the module's sources whose target matches `forbidden`.
std::vector<Violation> forbidden_includes(const std::string& module, const std::regex& forbidden) {
  const std::regex include_line(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  return matching_lines(module, [&](const std::string& line) {
    std::smatch m;
    return std::regex_search(line, m, include_line) && std::regex_search(m[1].str(), forbidden);
  });
}

std::string describe(const std::vector<Violation>& v) {
  std::string s;
  for (const auto& x : v) s += x.file + ":" + std::to_string(x.line) + ": " + x.text + "\n";
  return s;
}

const std::regex kMpiOrHdf5(R"(^(mpi\.h|mpi|H5Cpp\.h|hdf5\.h|H5[A-Za-z]*\.h|hdf5_hl\.h)$)");

// Every module of the source tree (a top-level folder with a CMakeLists.txt) but the tests, so a
// new module is checked without being listed here.
std::vector<std::string> modules_except(const std::string& allowed) {
  std::vector<std::string> modules;
  for (const auto& entry : fs::directory_iterator(source_dir())) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && fs::exists(entry.path() / "CMakeLists.txt") && name != "tests" &&
        name != allowed)
      modules.push_back(name);
  }
  return modules;
}

// Every line of the module's sources whose code (comments stripped) matches `forbidden`.
std::vector<Violation> forbidden_code(const std::string& module, const std::regex& forbidden) {
  return matching_lines(module, [&](const std::string& line) {
    return std::regex_search(line.substr(0, line.find("//")), forbidden);
  });
}

const std::regex kMpiHeader(R"(^(mpi\.h|mpi)$)");
// A call of the MPI C API (MPI_Send(...)); the type MPI_Comm and constants are no calls.
const std::regex kMpiCall(R"(\bP?MPI_[A-Z][A-Za-z_]*\s*\()");

// The MPI rules over `modules`: every include of mpi.h and every MPI call found.
std::vector<Violation> mpi_outside_its_room(const std::vector<std::string>& modules) {
  std::vector<Violation> found;
  for (const std::string& module : modules) {
    for (auto& v : forbidden_includes(module, kMpiHeader)) found.push_back(v);
    for (auto& v : forbidden_code(module, kMpiCall)) found.push_back(v);
  }
  return found;
}

// Points source_dir() at another tree while it lives (the planted-violation tests).
class ScopedSourceDir {
 public:
  explicit ScopedSourceDir(const fs::path& dir) {
    const char* previous = std::getenv("SOFTEVO_SOURCE_DIR");
    if (previous) saved_ = previous;
    setenv("SOFTEVO_SOURCE_DIR", dir.c_str(), 1);
  }
  ~ScopedSourceDir() {
    if (saved_) {
      setenv("SOFTEVO_SOURCE_DIR", saved_->c_str(), 1);
    } else {
      unsetenv("SOFTEVO_SOURCE_DIR");
    }
  }

 private:
  std::optional<std::string> saved_;
};

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
  const auto p = forbidden_includes("evo", std::regex(R"(^(physics|tasks|worker|master)/)"));
  EXPECT_TRUE(p.empty()) << describe(p);
}

TEST(ModuleRules, CommonDependsOnNoOtherModule) {
  const auto v = forbidden_includes("common", std::regex(R"(^(physics|tasks|evo|worker|master)/)"));
  EXPECT_TRUE(v.empty()) << describe(v);
  const auto m = forbidden_includes("common", kMpiOrHdf5);
  EXPECT_TRUE(m.empty()) << describe(m);
}

TEST(ModuleRules, TasksSeeOnlyCommonAndPhysics) {
  // A task observes the simulated robot (physics) and is asked by the worker, the master and
  // the tools; it never reaches up to them, nor into MPI or HDF5.
  const auto v = forbidden_includes("tasks", kMpiOrHdf5);
  EXPECT_TRUE(v.empty()) << describe(v);
  const auto m =
      forbidden_includes("tasks", std::regex(R"(^(evo|worker|master|validation|tools)/)"));
  EXPECT_TRUE(m.empty()) << describe(m);
}

TEST(ModuleRules, WorkerEvaluationLogicIsMpiFree) {
  // worker/ never includes MPI (the worker loop talks through mpi/) and never writes HDF5.
  const auto v = forbidden_includes("worker", kMpiOrHdf5);
  EXPECT_TRUE(v.empty()) << describe(v);
}

TEST(ModuleRules, OnlyTheMpiModuleIncludesOrCallsMpi) {
  const auto modules = modules_except("mpi");
  EXPECT_GE(modules.size(), 6u) << "the module scan found too few folders under " << source_dir();
  const auto v = mpi_outside_its_room(modules);
  EXPECT_TRUE(v.empty()) << describe(v);
}

TEST(ModuleRules, OnlyTheThinDriversUseTheMpiModule) {
  // In master/ and worker/ only the drivers (mpi_driver.*, worker_loop.*) may use mpi/: the
  // scheduling and the evaluation stay testable without MPI.
  std::vector<Violation> v;
  for (const char* module : {"master", "worker"}) {
    for (const auto& x : forbidden_includes(module, std::regex(R"(^mpi/)"))) {
      if (x.file.find("mpi_driver") == std::string::npos &&
          x.file.find("worker_loop") == std::string::npos)
        v.push_back(x);
    }
  }
  for (const char* module : {"common", "physics", "evo"}) {
    for (const auto& x : forbidden_includes(module, std::regex(R"(^mpi/)"))) v.push_back(x);
  }
  EXPECT_TRUE(v.empty()) << describe(v);
}

TEST(ModuleRules, MpiModuleDependsOnNoOtherModule) {
  std::vector<std::string> others = modules_except("mpi");
  std::string alternatives;
  for (const auto& m : others) alternatives += (alternatives.empty() ? "" : "|") + m;
  const auto v = forbidden_includes("mpi", std::regex("^(" + alternatives + ")/"));
  EXPECT_TRUE(v.empty()) << describe(v);
}

TEST(ModuleRules, MasterAndWorkerNeverIncludeEachOther) {
  // The program that joins them (tools/softevo_mpi.cpp) sits above both.
  const auto m = forbidden_includes("master", std::regex(R"(^worker/)"));
  EXPECT_TRUE(m.empty()) << describe(m);
  const auto w = forbidden_includes("worker", std::regex(R"(^master/)"));
  EXPECT_TRUE(w.empty()) << describe(w);
}

TEST(ModuleRules, MotionNeverSeesTheRendererAndSceneOnlyCommon) {
  // motion/ makes bodies and poses, the plain types of scene/; it does not depend on the
  // renderer for them. scene/ sits below motion/, render/ and view/.
  const auto m = forbidden_includes("motion", std::regex(R"(^render/)"));
  EXPECT_TRUE(m.empty()) << describe(m);
  std::string others;
  for (const auto& module : modules_except("common"))
    if (module != "scene") others += (others.empty() ? "" : "|") + module;
  const auto s = forbidden_includes("scene", std::regex("^(" + others + ")/"));
  EXPECT_TRUE(s.empty()) << describe(s);
}

TEST(ModuleRules, FabricateSeesOnlySceneRenderAndCommon) {
  // fabricate/ works on scene::Body (docs/architecture.md §1): the stiffness colours and PNG
  // writing of render/ and common/; never physics, evo, worker, io, motion, MPI or HDF5.
  std::string others;
  for (const auto& module : modules_except("common"))
    if (module != "scene" && module != "render" && module != "fabricate")
      others += (others.empty() ? "" : "|") + module;
  const auto f = forbidden_includes("fabricate", std::regex("^(" + others + ")/"));
  EXPECT_TRUE(f.empty()) << describe(f);
  const auto h = forbidden_includes("fabricate", kMpiOrHdf5);
  EXPECT_TRUE(h.empty()) << describe(h);
}

TEST(ModuleRules, DetectorFindsAPlantedViolation) {
  // The scanner must be able to fail: plant a file and check it is reported.
  const fs::path dir = fs::temp_directory_path() / "softevo_rules_probe";
  fs::create_directories(dir / "probe");
  std::ofstream(dir / "probe" / "x.cpp") << "#include <mpi.h>\n#include \"physics/model.hpp\"\n";
  std::vector<Violation> mpi, phys;
  {
    const ScopedSourceDir probe_tree(dir);
    mpi = forbidden_includes("probe", kMpiOrHdf5);
    phys = forbidden_includes("probe", std::regex(R"(^physics/)"));
  }
  fs::remove_all(dir);
  EXPECT_EQ(mpi.size(), 1u);
  EXPECT_EQ(phys.size(), 1u);
}

TEST(ModuleRules, DetectorFindsPlantedMpiAndCrossModuleViolations) {
  // A tree with an mpi/ module and tests/ (both may use MPI), a probe module that includes mpi.h
  // and calls MPI (a comment or a type is no call), and a master/ that includes worker/.
  const fs::path dir = fs::temp_directory_path() / "softevo_rules_probe_mpi";
  fs::remove_all(dir);
  for (const char* module : {"mpi", "probe", "master", "tests"}) {
    fs::create_directories(dir / module);
    std::ofstream(dir / module / "CMakeLists.txt") << "# probe\n";
  }
  std::ofstream(dir / "mpi" / "comm.cpp") << "#include <mpi.h>\nvoid f() { MPI_Barrier(c); }\n";
  std::ofstream(dir / "tests" / "t.cpp") << "#include <mpi.h>\n";
  std::ofstream(dir / "probe" / "x.cpp") << "#include <mpi.h>\n"
                                         << "// MPI_Send( in a comment is no call\n"
                                         << "MPI_Comm comm;  // a type is no call\n"
                                         << "int n = MPI_Send (buf, 1, MPI_BYTE, 0, 1, comm);\n";
  std::ofstream(dir / "master" / "y.hpp") << "#include \"worker/worker_loop.hpp\"\n";
  std::vector<std::string> modules;
  std::vector<Violation> mpi, cross;
  {
    const ScopedSourceDir probe_tree(dir);
    modules = modules_except("mpi");
    mpi = mpi_outside_its_room(modules);
    cross = forbidden_includes("master", std::regex(R"(^worker/)"));
  }
  fs::remove_all(dir);
  EXPECT_EQ(modules.size(), 2u);               // probe and master; mpi/ and tests/ are exempt
  ASSERT_EQ(mpi.size(), 2u) << describe(mpi);  // the include and the call in probe/x.cpp
  EXPECT_EQ(mpi[0].line, 1);
  EXPECT_EQ(mpi[1].line, 4);
  EXPECT_EQ(cross.size(), 1u);
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
