// Descriptions to and from Python in the scene file's terms (kernel/scene/scene_file.hpp): a body,
// joint, collider or ball given as a dict is written into a minimal scene's JSON text and read by
// the kernel's own scene reader (load_scene_text), so each field is checked as a scene file's is
// and an error names it the same way: "add_body: bodies[0].mass: must be > 0, got -1". No field
// is read here; this file only writes JSON (with nlohmann-json).
#include <cmath>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "tools/python/module.hpp"

namespace limber::python {
namespace {

using Json = nlohmann::ordered_json;

// A Python value as JSON (nlohmann-json builds the text): dicts (string keys), lists and tuples,
// NumPy arrays and scalars, str, bool, int, float and None. A non-finite float, a key that is not
// a string or any other type is a ModelError naming `call` and the value's path, as the scene
// reader names a field.
Json to_json(py::handle value, const std::string& path, std::string_view call) {
  const auto refuse = [&](std::string_view problem) { checks::fail(std::string(call) + ": " + path, problem); };
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) return value.cast<long long>();
  if (py::isinstance<py::float_>(value)) {
    const double number = value.cast<double>();
    if (!std::isfinite(number)) refuse("must be a finite number, got " + checks::format_number(number));
    return number;
  }
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::dict>(value)) {
    Json object = Json::object();
    for (const auto& [key, item] : value.cast<py::dict>()) {
      if (!py::isinstance<py::str>(key)) refuse("keys must be strings, got " + py::repr(key).cast<std::string>());
      const std::string name = key.cast<std::string>();
      object[name] = to_json(item, path.empty() ? name : path + "." + name, call);
    }
    return object;
  }
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    Json array = Json::array();
    for (const py::handle item : value) array.push_back(to_json(item, checks::indexed(path, array.size()), call));
    return array;
  }
  if (py::isinstance<py::array>(value) || py::isinstance(value, py::module_::import("numpy").attr("generic"))) {
    return to_json(value.attr("tolist")(), path, call);  // an array as nested lists, a scalar as its Python number
  }
  refuse("must be a number, string, bool, None, list or dict, got " + py::str(value.get_type().attr("__name__")).cast<std::string>());
  return nullptr;
}

py::list triple(const Vector3& v) { return py::cast(std::vector<double>{v.x(), v.y(), v.z()}); }

}  // namespace

Scene scene_of(std::string_view call, const py::dict& sections) {
  py::dict settings;
  settings["gravity"] = triple(Vector3(0, 0, -9.81)), settings["time_step"] = 0.01, settings["duration"] = 1.0;
  py::dict scene;
  scene["limber_scene"] = 1, scene["name"] = std::string(call), scene["settings"] = settings, scene["bodies"] = py::list();
  for (const auto& [key, value] : sections) scene[key] = value;
  return load_scene_text(to_json(scene, "", call).dump(), call);
}

py::dict body_dict(const Body& body) {
  py::dict shape;
  shape["type"] = body.shape.type == ShapeType::capsule ? "capsule" : "cylinder";
  shape["length"] = body.shape.length, shape["radius"] = body.shape.radius;
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
