// The `_softevo` extension module: the C++ half of the `softevo` Python package. The package
// (python/softevo/__init__.py) re-exports what is public; see its docstring.
#include <pybind11/pybind11.h>

#include "python/src/bindings.hpp"

PYBIND11_MODULE(_softevo, m) {
  m.doc() =
      "Compiled core of the softevo package (robots, configs, evaluation, stepping simulation, "
      "run archives). Use it through `import softevo`.";
  softevo::python::bind_errors(m);
  softevo::python::bind_robots(m);
  softevo::python::bind_evaluation(m);
  softevo::python::bind_archive(m);
  softevo::python::bind_evolution(m);
}
