// Descriptions to and from Python in the scene file's terms (kernel/scene/scene_file.hpp): a body,
// joint, collider or ball given as a dict is written into a minimal scene's JSON text and read by
// the kernel's own scene reader (load_scene_text), so each field is checked as a scene file's is
// and an error names it the same way: "add_body: bodies[0].mass: must be > 0, got -1". No field
// is read here; this file only writes JSON (with nlohmann-json). What JSON cannot hold is refused
// here, as a ModelError naming the path: a dict or list that contains itself, nesting deeper than
// 64 levels, a non-finite number, text with a lone surrogate.
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "tools/python/module.hpp"

namespace limber::python {
namespace {

using Json = nlohmann::ordered_json;

// How deep a description may nest dicts and lists (the description itself is level 1): far past
// any scene file's (a mesh's triangles are level 3), and short of what a recursive reader's stack
// holds. The minimal scene and its section's list enclose the description: two levels more.
constexpr std::size_t kMaxDepth = 64;
constexpr std::size_t kAboveDescription = 2;

// A Python int as JSON: exact when it fits 64 bits, else the nearest double (finite, or refused).
Json integer(py::handle value, const std::function<void(std::string_view)>& refuse) {
  int overflow = 0;
  const long long exact = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (exact == -1 && PyErr_Occurred()) throw py::error_already_set();
  if (overflow == 0) return exact;
  const double rounded = PyLong_AsDouble(value.ptr());
  if (rounded == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    refuse("must be a finite number, got an integer past the largest double (~1.8e308)");
  }
  return rounded;
}

// A Python str as JSON: its UTF-8 (a lone surrogate, which UTF-8 cannot hold, refused).
Json utf8_text(py::handle value, const std::function<void(std::string_view)>& refuse) {
  Py_ssize_t size = 0;
  const char* data = PyUnicode_AsUTF8AndSize(value.ptr(), &size);
  if (data == nullptr) {
    PyErr_Clear();
    refuse("must be text UTF-8 can hold, got " + py::repr(value).cast<std::string>());
  }
  return std::string(data, static_cast<std::size_t>(size));
}

// A Python value as JSON (nlohmann-json builds the text): dicts (string keys), lists and tuples,
// NumPy arrays and scalars, str, bool, int, float and None. A non-finite float, a key that is not
// a string, a dict or list that contains itself (`enclosing`: the containers around `value`) or
// nests deeper than kMaxDepth, or any other type is a ModelError naming `call` and the value's
// path, as the scene reader names a field.
Json to_json(py::handle value, const std::string& path, std::string_view call, std::vector<PyObject*>& enclosing) {
  const std::function<void(std::string_view)> refuse = [&](std::string_view problem) { checks::fail(std::string(call) + ": " + path, problem); };
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) return integer(value, refuse);
  if (py::isinstance<py::float_>(value)) {
    const double number = value.cast<double>();
    if (!std::isfinite(number)) refuse("must be a finite number, got " + checks::format_number(number));
    return number;
  }
  if (py::isinstance<py::str>(value)) return utf8_text(value, refuse);
  const bool dict = py::isinstance<py::dict>(value), sequence = py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value);
  const bool array = py::isinstance<py::array>(value) || py::isinstance(value, py::module_::import("numpy").attr("generic"));
  if (!dict && !sequence && !array) {
    refuse("must be a number, string, bool, None, list or dict, got " + py::str(value.get_type().attr("__name__")).cast<std::string>());
  }
  if (std::find(enclosing.begin(), enclosing.end(), value.ptr()) != enclosing.end()) refuse("contains itself (a cycle)");
  if (enclosing.size() >= kMaxDepth + kAboveDescription) refuse("nests dicts and lists deeper than " + std::to_string(kMaxDepth) + " levels");
  enclosing.push_back(value.ptr());
  Json out;
  if (array) {
    out = to_json(value.attr("tolist")(), path, call, enclosing);  // an array as nested lists, a scalar as its Python number
  } else if (dict) {
    out = Json::object();
    for (const auto& [key, entry] : value.cast<py::dict>()) {
      if (!py::isinstance<py::str>(key)) refuse("keys must be strings, got " + py::repr(key).cast<std::string>());
      const std::string name = utf8_text(key, refuse);
      const py::object item = py::reinterpret_borrow<py::object>(entry);  // held: a conversion may run Python code
      out[name] = to_json(item, path.empty() ? name : path + "." + name, call, enclosing);
    }
  } else {
    // The list's or tuple's own items (a subclass's __len__ and __getitem__ left out), each held while converted.
    const bool list = PyList_Check(value.ptr());
    const auto size = [&] { return list ? PyList_GET_SIZE(value.ptr()) : PyTuple_GET_SIZE(value.ptr()); };
    out = Json::array();
    for (Py_ssize_t k = 0; k < size(); ++k) {
      const py::object item = py::reinterpret_borrow<py::object>(list ? PyList_GET_ITEM(value.ptr(), k) : PyTuple_GET_ITEM(value.ptr(), k));
      out.push_back(to_json(item, checks::indexed(path, static_cast<std::size_t>(k)), call, enclosing));
    }
  }
  enclosing.pop_back();
  return out;
}

py::list triple(const Vector3& v) { return py::cast(std::vector<double>{v.x(), v.y(), v.z()}); }

// A body's shape as the scene file gives it: a box's or ellipsoid's half_extents and rotation
// (w, x, y, z), a cylinder's or capsule's length and radius.
py::dict shape_dict(const Shape& given) {
  py::dict shape;
  shape["type"] = std::string(shape_type_name(given.type));
  if (has_half_extents(given)) {
    const Eigen::Quaterniond& q = given.rotation;
    shape["half_extents"] = triple(given.half_extents);
    shape["rotation"] = py::cast(std::vector<double>{q.w(), q.x(), q.y(), q.z()});
  } else {
    shape["length"] = given.length, shape["radius"] = given.radius;
  }
  return shape;
}

}  // namespace

Scene scene_of(std::string_view call, const py::dict& sections) {
  py::dict settings;
  settings["gravity"] = triple(Vector3(0, 0, -9.81)), settings["time_step"] = 0.01, settings["duration"] = 1.0;
  py::dict scene;
  scene["limber_scene"] = 1, scene["name"] = std::string(call), scene["settings"] = settings, scene["bodies"] = py::list();
  for (const auto& [key, value] : sections) scene[key] = value;
  std::vector<PyObject*> enclosing;
  return load_scene_text(to_json(scene, "", call, enclosing).dump(), call);
}

py::dict body_dict(const Body& body) {
  const py::dict shape = shape_dict(body.shape);
  py::dict out;
  out["name"] = body.name, out["shape"] = shape;
  if (!body.point_masses.empty()) {
    py::list lumps;
    for (const PointMass& lump : body.point_masses) {
      py::dict entry;
      entry["position"] = triple(lump.position), entry["mass"] = lump.mass, entry["radius"] = lump.radius;
      lumps.append(entry);
    }
    out["point_masses"] = lumps;
  } else {
    out["mass"] = body.mass;
  }
  if (body.inertial) {
    const Eigen::Matrix3d& i = body.inertial->inertia;
    py::dict inertial;
    inertial["centre_of_mass"] = triple(body.inertial->centre_of_mass);
    inertial["inertia"] = py::cast(std::vector<double>{i(0, 0), i(1, 1), i(2, 2), i(0, 1), i(0, 2), i(1, 2)});
    out["inertial"] = inertial;
  }
  out["position"] = triple(body.position), out["axis"] = triple(body.axis);
  out["linear_velocity"] = triple(body.linear_velocity), out["angular_velocity"] = triple(body.angular_velocity);
  py::dict collision;
  collision["group"] = body.collision.group, collision["mask"] = body.collision.mask;
  out["collision"] = collision;
  return out;
}

}  // namespace limber::python
