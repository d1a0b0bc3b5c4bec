"""Build hook of pyproject.toml: `pip install .` configures and builds the softevo_python CMake
target (the extension _softevo and the package's pure-Python modules, assembled in
<build>/python/softevo) and installs that package.

The CMake build tree is build-pip/ in the source tree (incremental on a second install);
SOFTEVO_CMAKE_ARGS adds configure options (e.g. "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache").
"""

import os
import pathlib
import shlex
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent
(ROOT / "build-pip").mkdir(exist_ok=True)


class CMakeBuild(build_ext):
    """Builds the whole package with CMake instead of compiling the extension itself."""

    def build_extension(self, ext: Extension) -> None:
        build = ROOT / "build-pip"
        args = ["-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release", f"-DPython_EXECUTABLE={sys.executable}",
                "-DSOFTEVO_REQUIRE_PYTHON=ON", "-DSOFTEVO_REQUIRE_HDF5=ON"]
        try:
            import pybind11
            args.append(f"-Dpybind11_DIR={pybind11.get_cmake_dir()}")
        except ImportError:
            pass  # CMake looks for pybind11 itself (Debian: pybind11-dev)
        args += shlex.split(os.environ.get("SOFTEVO_CMAKE_ARGS", ""))
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), *args], check=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "softevo_python"], check=True)
        package = build / "python" / "softevo"
        target = pathlib.Path(self.build_lib) / "softevo"
        target.mkdir(parents=True, exist_ok=True)
        for f in package.iterdir():
            if f.is_file():
                self.copy_file(str(f), str(target / f.name))


# setuptools' own build folders and metadata go under build-pip/ too (its default, build/, is
# the CMake build of the README).
setup(ext_modules=[Extension("softevo._softevo", sources=[])], cmdclass={"build_ext": CMakeBuild},
      options={"build": {"build_base": "build-pip/setuptools"},
               "egg_info": {"egg_base": "build-pip"}})
