// The parts of the `_softevo` extension module (the compiled half of the `softevo` Python
// package, python/softevo/), one function per part, called by module.cpp in this order.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <vector>

namespace softevo::python {

// Exceptions: robot file and config errors are ValueError subclasses, archive errors OSError.
void bind_errors(pybind11::module_& m);
// Robot (softevo.robot/1), Config, develop().
void bind_robots(pybind11::module_& m);
// evaluate(), Simulation, Controller.
void bind_evaluation(pybind11::module_& m);
// The run archive reader (io::Archive).
void bind_archive(pybind11::module_& m);
// softevo.evolve: a run driven from Python on worker threads (RunError).
void bind_evolution(pybind11::module_& m);

// A 1-D numpy array holding a copy of `values`.
template <typename T>
pybind11::array_t<T> array_of(const std::vector<T>& values) {
  return pybind11::array_t<T>(static_cast<pybind11::ssize_t>(values.size()), values.data());
}

}  // namespace softevo::python
