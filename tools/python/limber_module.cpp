// limber's Python module, _limber (the package tools/python/limber re-exports it): scenes, and
// the World with its bulk state as NumPy arrays. Units are SI (m, kg, s, N, N·m, rad); arrays are
// float64, one row per body in Model order. ModelError and WorldError reach Python as
// limber.ModelError and limber.WorldError (ValueError), carrying the C++ message whole (a bad
// scene field names the file and the field). World.step releases the GIL, so Worlds on two
// Python threads step at once; one World is not to be used from two threads at a time.
#include <array>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

namespace py = pybind11;
using namespace limber;

namespace {

using Array = py::array_t<double, py::array::c_style>;

constexpr std::array kMethods{Method::particles, Method::springs, Method::lagrange, Method::featherstone};

Method method_named(const std::string& name) {
  for (const Method method : kMethods) {
    if (method_name(method) == name) return method;
  }
  throw py::value_error("method: '" + name + "' is not one of 'particles', 'springs', 'lagrange', 'featherstone'");
}

const char* status_name(StepStatus status) {
  switch (status) {
    case StepStatus::ok: return "ok";
    case StepStatus::diverged_non_finite: return "diverged_non_finite";
    case StepStatus::diverged_speed: return "diverged_speed";
    case StepStatus::diverged_energy: return "diverged_energy";
    case StepStatus::diverged_joint_gap: return "diverged_joint_gap";
    case StepStatus::invalid_time_step: return "invalid_time_step";
  }
  return "unknown";
}

void put(double* row, const Eigen::Vector3d& v) { row[0] = v.x(), row[1] = v.y(), row[2] = v.z(); }

// An (rows × columns) float64 array filled by `fill(row, pointer to its first value)`.
template <typename Fill>
Array rows(std::size_t count, py::ssize_t columns, Fill fill) {
  Array out({static_cast<py::ssize_t>(count), columns});
  double* data = out.mutable_data();
  for (std::size_t r = 0; r < count; ++r) fill(r, data + static_cast<py::ssize_t>(r) * columns);
  return out;
}

Eigen::Vector3d vector3(const Array& in, const char* what) {
  if (in.ndim() != 1 || in.shape(0) != 3) throw py::value_error(std::string(what) + ": expected 3 numbers");
  return {in.at(0), in.at(1), in.at(2)};
}

Eigen::VectorXd vector(const Array& in, const char* what) {
  if (in.ndim() != 1) throw py::value_error(std::string(what) + ": expected a one-dimensional array");
  return Eigen::Map<const Eigen::VectorXd>(in.data(), in.shape(0));
}

py::dict observation(const Observation& o) {
  py::dict out;
  out["time"] = o.time;
  out["max_joint_gap"] = o.max_joint_gap, out["rms_joint_gap"] = o.rms_joint_gap;
  out["max_link_stretch"] = o.max_link_stretch;
  out["kinetic_energy"] = o.kinetic_energy, out["potential_energy"] = o.potential_energy, out["energy"] = o.energy();
  out["body_centre_of_mass"] = std::array{o.body_centre_of_mass.x(), o.body_centre_of_mass.y(), o.body_centre_of_mass.z()};
  out["linear_momentum"] = std::array{o.linear_momentum.x(), o.linear_momentum.y(), o.linear_momentum.z()};
  out["islands"] = o.islands, out["islands_sleeping"] = o.islands_sleeping;
  out["limit_violation"] = o.joints.limit_violation, out["drive_error"] = o.joints.drive_error;
  return out;
}

void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", "A loaded scene: its Model (bodies, joints, settings) and the methods' settings.")
      .def_property_readonly("name", [](const Scene& s) { return s.model.name; })
      .def_property_readonly("body_names", [](const Scene& s) {
        std::vector<std::string> names;
        for (const Body& body : s.model.bodies) names.push_back(body.name);
        return names;
      })
      .def_property_readonly("joint_names", [](const Scene& s) {
        std::vector<std::string> names;
        for (const Joint& joint : s.model.joints) names.push_back(joint.name);
        return names;
      })
      .def_property_readonly("time_step", [](const Scene& s) { return s.model.settings.time_step; }, "s")
      .def_property_readonly("notes", [](const Scene& s) { return s.notes; }, "what a model file's loader dropped or approximated");
  m.def(
      "load_scene",
      [](const std::string& path, std::optional<std::string> variant, std::optional<long> links, std::optional<long> copies) {
        SceneOptions options;
        options.variant = std::move(variant), options.links = links, options.copies = copies;
        return load_scene_file(path, options);
      },
      py::arg("path"), py::kw_only(), py::arg("variant") = py::none(), py::arg("links") = py::none(), py::arg("copies") = py::none(),
      "Loads a scene file: limber's JSON, MuJoCo's MJCF (.xml) or a URDF robot (.urdf). Raises ModelError naming the file and field.");
}

using WorldClass = py::class_<World>;

// Construction, stepping and what identifies the World.
void bind_stepping(WorldClass& world) {
  world.def(py::init([](const Scene& scene, const std::string& method) { return World(scene, method_named(method)); }), py::arg("scene"),
           py::arg("method") = "particles", "method: 'particles', 'springs', 'lagrange' or 'featherstone', with the scene's settings")
      .def(
          "step", [](World& w, std::optional<double> dt) {
            StepStatus status;
            {
              py::gil_scoped_release release;
              status = dt ? w.step(*dt) : w.step();
            }
            return status_name(status);
          },
          py::arg("dt") = py::none(), "One step of dt s (the scene's time step by default). Returns the status: 'ok' or why not.")
      .def_property_readonly("time", &World::time, "s")
      .def_property_readonly("method", [](const World& w) { return std::string(method_name(w.method())); })
      .def_property_readonly("body_names", [](const World& w) {
        std::vector<std::string> names;
        for (const BodyId id : w.bodies()) names.push_back(w.body_description(id).name);
        return names;
      });
}

// The bodies' state as arrays, and the observers.
void bind_read_outs(WorldClass& world) {
  world.def(
          "poses", [](const World& w) {
            std::vector<Pose> poses(w.bodies().size());
            w.poses(poses);
            Array position = rows(poses.size(), 3, [&](std::size_t r, double* row) { put(row, poses[r].position); });
            Array orientation = rows(poses.size(), 4, [&](std::size_t r, double* row) {
              const Eigen::Quaterniond& q = poses[r].orientation;
              row[0] = q.w(), row[1] = q.x(), row[2] = q.y(), row[3] = q.z();
            });
            return py::make_tuple(position, orientation);
          },
          "(positions N×3 m, orientations N×4 w x y z): each body frame's origin and rotation (body → world)")
      .def(
          "motions", [](const World& w) {
            std::vector<Motion> motions(w.bodies().size());
            w.motions(motions);
            Array linear = rows(motions.size(), 3, [&](std::size_t r, double* row) { put(row, motions[r].linear); });
            Array angular = rows(motions.size(), 3, [&](std::size_t r, double* row) { put(row, motions[r].angular); });
            return py::make_tuple(linear, angular);
          },
          "(linear N×3 m/s of each body frame's origin, angular N×3 rad/s), world")
      .def("observe", [](const World& w) { return observation(w.observe()); },
           "energy (J), momentum (kg·m/s), joint gaps (relative to link length), limits (rad) as a dict");
}

// Loads over the next step, and the actuators' controls.
void bind_loads(WorldClass& world) {
  world.def(
          "apply_force", [](World& w, const std::string& body, const Array& force, const Array& point) {
            w.apply_force(w.body(body), vector3(force, "force"), vector3(point, "point"));
          },
          py::arg("body"), py::arg("force"), py::arg("point"), "A force (N, world) at a world point (m) over the next step")
      .def(
          "apply_impulse", [](World& w, const std::string& body, const Array& impulse, const Array& point) {
            w.apply_impulse(w.body(body), vector3(impulse, "impulse"), vector3(point, "point"));
          },
          py::arg("body"), py::arg("impulse"), py::arg("point"), "An impulse (N·s, world) at a world point (m)")
      .def(
          "apply_torque", [](World& w, const std::string& body, const Array& torque) { w.apply_torque(w.body(body), vector3(torque, "torque")); },
          py::arg("body"), py::arg("torque"), "A torque (N·m, world) about the body's centre of mass over the next step")
      .def(
          "apply_joint_torque", [](World& w, const std::string& joint, const Array& torque) {
            w.apply_joint_torque(w.joint(joint), vector3(torque, "torque"));
          },
          py::arg("joint"), py::arg("torque"), "+torque (N·m, world) on the joint's outboard body, −torque on its inboard one")
      .def(
          "set_controls", [](World& w, const Array& controls) {
            const Eigen::VectorXd values = vector(controls, "controls");
            w.set_controls(std::span<const double>(values.data(), static_cast<std::size_t>(values.size())));
          },
          py::arg("controls"), "The actuators' controls, one per actuator in the scene's order")
      .def("controls", [](const World& w) { return std::vector<double>(w.controls().begin(), w.controls().end()); });
}

// Joint space (Featherstone; the other methods raise WorldError naming the call).
void bind_joint_space(WorldClass& world) {
  world.def("joint_space_names", &World::joint_space_names)
      .def("joint_positions", &World::joint_positions, "q, nq (featherstone; the others raise WorldError)")
      .def("joint_velocities", &World::joint_velocities, "v, nv")
      .def(
          "set_joint_state", [](World& w, const Array& q, const Array& v) { w.set_joint_state(vector(q, "q"), vector(v, "v")); }, py::arg("q"),
          py::arg("v"))
      .def("joint_mass_matrix", &World::joint_mass_matrix, "M(q), nv × nv, with armature")
      .def("joint_bias_forces", &World::joint_bias_forces, "C(q, v), nv")
      .def("joint_passive_forces", &World::joint_passive_forces, "springs, dampers and actuators, nv")
      .def(
          "joint_accelerations", [](const World& w, const Array& forces) { return w.joint_accelerations(vector(forces, "forces")); },
          py::arg("forces"), "M⁻¹(τ − C), nv")
      .def(
          "inverse_dynamics", [](const World& w, const Array& accelerations) { return w.inverse_dynamics(vector(accelerations, "accelerations")); },
          py::arg("accelerations"), "M v̇ + C, nv")
      .def(
          "joint_reactions", [](const World& w, const Array& accelerations) {
            const std::vector<JointReaction> r = w.joint_reactions(vector(accelerations, "accelerations"));
            return py::make_tuple(rows(r.size(), 3, [&](std::size_t k, double* row) { put(row, r[k].force); }),
                                  rows(r.size(), 3, [&](std::size_t k, double* row) { put(row, r[k].torque); }));
          },
          py::arg("accelerations"),
          "(forces J×3 N, torques J×3 N·m about each outboard anchor): what each joint's inboard body exerts on its outboard body, world");
}

}  // namespace

PYBIND11_MODULE(_limber, m) {
  m.doc() = "limber: articulated bodies with distributed mass (https://github.com/…/limber; README.md)";
  py::register_exception<ModelError>(m, "ModelError", PyExc_ValueError);
  py::register_exception<WorldError>(m, "WorldError", PyExc_ValueError);
  m.attr("methods") = std::vector<std::string>{"particles", "springs", "lagrange", "featherstone"};
  bind_scene(m);
  WorldClass world(m, "World", "One scene under one method, stepped and read (kernel/world/world.hpp).");
  bind_stepping(world);
  bind_read_outs(world);
  bind_loads(world);
  bind_joint_space(world);
}
