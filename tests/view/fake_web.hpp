// A stand-in for view/web: the six files the server and the export read (view/server.hpp
// load_web_files), with markers and a hostile string, without npm ci.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/io/tmp_dir.hpp"

namespace softevo::test {

struct FakeWeb {
  TmpDir dir;
  FakeWeb() {
    const auto put = [&](const std::string& name, const std::string& text) {
      std::filesystem::create_directories(std::filesystem::path(dir.file(name)).parent_path());
      std::ofstream(dir.file(name)) << text;
    };
    put("index.html",
        "<html><head><!-- softevo:head --><!-- /softevo:head --></head><body>"
        "<!-- softevo:app --><!-- /softevo:app --></body></html>");
    put("app.js", "const s = '</SCRIPT><b>';\n");
    put("plots.js", "export {};\n");
    put("style.css", "body {}\n");
    put("node_modules/three/build/three.module.min.js", "export {};\n");
    put("node_modules/three/examples/jsm/controls/OrbitControls.js", "export {};\n");
  }
};

}  // namespace softevo::test
