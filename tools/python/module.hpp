// What the Python module's binding files share (tools/python/*.cpp): array conversions and the
// names of the C++ enums as Python sees them. Arrays are float64 and C-ordered, one row per
// body (or joint, ball) in the World's order.
#pragma once

#include <string>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "limber/kernel/world/world.hpp"

namespace limber::python {

namespace py = pybind11;
using Array = py::array_t<double, py::array::c_style>;
using WorldClass = py::class_<World>;

/// A bad World option (a `limber run` flag's name or value): limber.OptionError, a ValueError.
class OptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// StepStatus as Python reads it: "ok", "diverged_non_finite", ...
const char* status_name(StepStatus status);

inline void put(double* row, const Eigen::Vector3d& v) { row[0] = v.x(), row[1] = v.y(), row[2] = v.z(); }

/// An (rows × columns) float64 array filled by `fill(row, pointer to its first value)`.
template <typename Fill>
Array rows(std::size_t count, py::ssize_t columns, Fill fill) {
  Array out({static_cast<py::ssize_t>(count), columns});
  double* data = out.mutable_data();
  for (std::size_t r = 0; r < count; ++r) fill(r, data + static_cast<py::ssize_t>(r) * columns);
  return out;
}

/// Three numbers (a 3-vector argument named `what`), or ValueError naming it.
Eigen::Vector3d vector3(const Array& in, const char* what);
/// A one-dimensional array as a vector, or ValueError naming `what`.
Eigen::VectorXd vector(const Array& in, const char* what);

/// World's stepping and metered runs (run.cpp): step, run.
void bind_running(WorldClass& world);

}  // namespace limber::python
