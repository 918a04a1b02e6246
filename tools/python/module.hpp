// What the Python module's binding files share (tools/python/*.cpp): array conversions and the
// names of the C++ enums as Python sees them. Arrays are float64 and C-ordered, one row per
// body (or joint, ball) in the World's order.
#pragma once

#include <algorithm>
#include <initializer_list>
#include <optional>
#include <array>
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "limber/kernel/world/world.hpp"
#include "tools/python/locked_world.hpp"

namespace limber::python {

namespace py = pybind11;
using Array = py::array_t<double, py::array::c_style>;

/// A bad World option (a `limber run` flag's name or value): limber.OptionError, a ValueError.
class OptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// `bytes` as Python text: UTF-8, any byte that is not shown escaped ("caf\xe9").
py::str text(std::string_view bytes);

inline void put(double* row, const Eigen::Vector3d& v) { row[0] = v.x(), row[1] = v.y(), row[2] = v.z(); }

/// An (rows × columns) float64 array filled by `fill(row, pointer to its first value)`.
template <typename Fill>
Array rows(std::size_t count, py::ssize_t columns, Fill fill) {
  Array out({static_cast<py::ssize_t>(count), columns});
  double* data = out.mutable_data();
  for (std::size_t r = 0; r < count; ++r) fill(r, data + static_cast<py::ssize_t>(r) * columns);
  return out;
}

/// Three numbers (a 3-vector argument named `what`), or WorldError naming it.
Eigen::Vector3d vector3(const Array& in, const char* what);
/// An optional 3-vector argument: vector3(*in, what), or `otherwise` when it is None.
inline Eigen::Vector3d vector3_or(const std::optional<Array>& in, const Eigen::Vector3d& otherwise, const char* what) {
  return in ? vector3(*in, what) : otherwise;
}
/// A one-dimensional array as a vector, or WorldError naming `what`.
Eigen::VectorXd vector(const Array& in, const char* what);
/// Four numbers w, x, y, z (a quaternion argument named `what`), or WorldError naming it.
Eigen::Quaterniond quaternion(const Array& in, const char* what);

/// A one-dimensional float64 array of `values` (a 3-vector, a quaternion w x y z).
inline Array numbers(std::initializer_list<double> values) {
  Array out(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}
inline Array numbers(const Eigen::Vector3d& v) { return numbers({v.x(), v.y(), v.z()}); }

/// The scene that `sections` (top-level scene-file entries, e.g. {"bodies": [description]}) make
/// over a minimal valid scene, read by the kernel's scene reader (scene_elements.cpp): a Python
/// element checked as a scene file's is. Throws ModelError "<call>: <path>: <problem>", also for
/// what JSON cannot hold: a dict or list containing itself or nested deeper than 64 levels (the
/// description itself is level 1), a non-finite number, text with a lone surrogate.
Scene scene_of(std::string_view call, const py::dict& sections);
/// A body's Model entry as a scene file's "bodies" entry: what scene_of reads back to it.
py::dict body_dict(const Body& body);

/// World.poses: every body's (positions N×3, orientations N×4) into `out`'s two arrays (None: new
/// ones), returned; ValueError naming the array when `out` is not two writeable C-contiguous
/// float64 arrays of those shapes.
py::object read_poses(const World& world, const py::object& out);
/// read_poses in two halves: the arrays `out` names, checked (or new ones), then filled.
std::array<py::array, 2> pose_arrays(const World& world, const py::object& out);
void fill_poses(const World& world, std::array<py::array, 2>& arrays);

/// World's stepping and metered runs (run.cpp): step, run.
void bind_running(WorldMethods& world);
/// limber.Ball and limber.Pin, the handles of balls and held points (edits.cpp); before the World.
void bind_handles(py::module_& m);
/// World's structural edits, held points, teleports and sleep (edits.cpp).
void bind_edits(WorldMethods& world);
/// World's step report, segments, one body's pose, motion and description, drives (reports.cpp).
void bind_report_calls(WorldMethods& world);
/// The model generators returning a limber.Scene: chain, tree, grid, humanoid_pile, copies (generators.cpp).
void bind_generators(py::module_& m);

}  // namespace limber::python
