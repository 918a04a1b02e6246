// limber's Python module, _limber (the package tools/python/limber re-exports it): scenes, and
// the World with its bulk state as NumPy arrays. Units are SI (m, kg, s, N, N·m, rad); arrays are
// float64, one row per body in Model order. ModelError, WorldError and OptionError reach Python as
// limber.ModelError, limber.WorldError and limber.OptionError (ValueError), carrying the C++
// message whole (a bad scene field names the file and the field). World.step and World.run
// release the GIL, so Worlds on two Python threads step at once; one World takes one call at a
// time, whatever the thread (locked_world.hpp). Text reaches Python as UTF-8: the scene readers
// refuse a name that is not, and a message or note quoting such bytes shows them escaped.
#include <algorithm>
#include <array>
#include <cctype>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/world/world.hpp"
#include "tools/cli/cli.hpp"
#include "tools/cli/run_flags.hpp"
#include "tools/python/module.hpp"

using namespace limber;
using namespace limber::python;

namespace limber::python {

Eigen::Vector3d vector3(const Array& in, const char* what) {
  if (in.ndim() != 1 || in.shape(0) != 3) throw WorldError(std::string(what) + ": expected 3 numbers");
  return {in.at(0), in.at(1), in.at(2)};
}

py::str text(std::string_view bytes) {
  PyObject* decoded = PyUnicode_DecodeUTF8(bytes.data(), static_cast<Py_ssize_t>(bytes.size()), "backslashreplace");
  if (decoded == nullptr) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(decoded);
}

Eigen::VectorXd vector(const Array& in, const char* what) {
  if (in.ndim() != 1) throw WorldError(std::string(what) + ": expected a one-dimensional array");
  return Eigen::Map<const Eigen::VectorXd>(in.data(), in.shape(0));
}

}  // namespace limber::python

namespace {

// A keyword option as `limber run` spells it: "newton_iterations" → "--newton-iterations".
std::string flag_name(const std::string& keyword) {
  std::string flag = "--" + keyword;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

// OptionError "World: --flag: expects INT, got <got>": a value `option` cannot take.
[[noreturn]] void refuse_value(const std::string& flag, const CLI::Option& option, const std::string& got) {
  throw OptionError("World: " + flag + ": expects " + option.get_type_name() + (option.get_expected_max() > 1 ? " values" : "") +
                    ", got " + got);
}

// A Python option value's text for the command line (str() of it: a float's shortest exact
// spelling), or OptionError naming `flag` when it is not one value CLI11 can read.
std::string option_text(py::handle value, const std::string& flag, const CLI::Option& option) {
  const auto refuse = [&](const std::string& got) { refuse_value(flag, option, got); };
  if (py::isinstance<py::bool_>(value)) refuse(py::repr(value).cast<std::string>());
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) || py::isinstance<py::dict>(value) ||
      py::isinstance<py::set>(value) || py::isinstance<py::array>(value)) {
    refuse("a " + py::str(value.get_type().attr("__name__")).cast<std::string>());
  }
  const py::str text = py::str(value);
  Py_ssize_t size = 0;
  const char* data = PyUnicode_AsUTF8AndSize(text.ptr(), &size);
  if (data == nullptr) {
    PyErr_Clear();
    refuse("text UTF-8 cannot hold");
  }
  return std::string(data, static_cast<std::size_t>(size));
}

// `flag=value` refused, naming the flag and the type it expects, when CLI11 cannot convert the
// value (CLI11's own message names neither plainly: "Could not convert: --iterations = --dt");
// every other problem is left to the whole parse, which names it.
void require_convertible(const std::string& flag, const std::string& value, const CLI::Option& option) {
  CLI::App app;
  cli::RunFlags flags;
  cli::add_run_flags(app, flags);
  const std::string argument = flag + "=" + value;
  const std::array<const char*, 2> argv{"limber run", argument.c_str()};
  try {
    app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ConversionError&) {
    refuse_value(flag, option, "'" + value + "'");
  } catch (const CLI::Error&) {
  }
}

// World options (Python keywords) as `limber run`'s arguments, `--flag=value` so that no value is
// read as a flag: a switch's True is the bare flag, False none; a sequence is comma-joined, its
// items single values; anything else its str(). Refused with OptionError naming the keyword: a
// name that is not a run flag's (or is --help, which CLI11 would answer with its help text), a
// switch given anything but a bool, a value that is not one (True, a nested list, a dict) or that
// CLI11 cannot convert to the flag's type.
std::vector<std::string> run_arguments(const std::string& method, const py::dict& options) {
  CLI::App app;  // the run flags, to tell switches from values and name their types
  cli::RunFlags flags;
  cli::add_run_flags(app, flags);
  std::vector<std::string> arguments{"--method=" + method};
  for (const auto& [key, value] : options) {
    const std::string keyword = py::str(key);
    const bool name = !keyword.empty() && std::isalpha(static_cast<unsigned char>(keyword[0])) &&
                      std::all_of(keyword.begin(), keyword.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
    if (!name) throw OptionError("World: '" + keyword + "' is not an option name (limber run's flags with '_' for '-', e.g. newton_iterations)");
    const std::string flag = flag_name(keyword);
    const CLI::Option* option = app.get_option_no_throw(flag);
    if (option == nullptr || option == app.get_help_ptr()) {
      throw OptionError("World: " + flag + ": is not an option of a World (limber run --help lists limber run's flags)");
    }
    if (option->get_expected_max() == 0) {  // a switch
      if (!py::isinstance<py::bool_>(value)) {
        throw OptionError("World: " + flag + ": is a switch (True or False), got " + py::repr(value).cast<std::string>());
      }
      if (value.cast<bool>()) arguments.push_back(flag);
      continue;
    }
    std::string text;
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
      const py::sequence items = py::reinterpret_borrow<py::sequence>(value);
      for (std::size_t k = 0; k < items.size(); ++k) {
        if (k > 0) text += ',';
        text += option_text(items[k], flag, *option);
      }
    } else {
      text = option_text(value, flag, *option);
    }
    require_convertible(flag, text, *option);
    arguments.push_back(flag + "=" + text);
  }
  return arguments;
}

// World(scene, method, options): the scene's copy with `limber run`'s flags applied. Options
// that do not go together (the World's std::invalid_argument) are OptionErrors too.
std::unique_ptr<LockedWorld> world_with_options(Scene scene, const std::string& method, const py::dict& options) {
  try {
    const WorldOptions world_options = cli::options_for_scene(scene, run_arguments(method, options));
    return std::make_unique<LockedWorld>(World(std::move(scene.model), world_options), method);
  } catch (const ModelError&) {
    throw;
  } catch (const OptionError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& error) {
    throw OptionError(std::string("World: ") + error.what());
  }
}

py::dict observation(const World& w, const Observation& o) {
  py::dict out;
  out["time"] = o.time;
  out["max_joint_gap"] = o.max_joint_gap, out["rms_joint_gap"] = o.rms_joint_gap;
  out["widest_joint"] = o.widest_joint < 0 ? py::object(py::none()) : py::object(text(w.model().joints[static_cast<std::size_t>(o.widest_joint)].name));
  out["max_link_stretch"] = o.max_link_stretch;
  out["kinetic_energy"] = o.kinetic_energy, out["potential_energy"] = o.potential_energy, out["energy"] = o.energy();
  out["body_centre_of_mass"] = std::array{o.body_centre_of_mass.x(), o.body_centre_of_mass.y(), o.body_centre_of_mass.z()};
  out["linear_momentum"] = std::array{o.linear_momentum.x(), o.linear_momentum.y(), o.linear_momentum.z()};
  out["islands"] = o.islands, out["islands_sleeping"] = o.islands_sleeping;
  out["limit_violation"] = o.joints.limit_violation, out["drive_error"] = o.joints.drive_error;
  out["deepest_penetration"] = o.penetration.depth, out["penetration"] = text(study::penetration_place(w.model(), o.penetration));
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
      .def_property_readonly(
          "notes", [](const Scene& s) {
            py::list notes;  // a file's text, quoted: bytes that are not UTF-8 shown escaped
            for (const std::string& note : s.notes) notes.append(text(note));
            return notes;
          },
          "what a model file's loader dropped or approximated");
  m.def(
      "load_scene",
      [](const std::string& path, std::optional<std::string> body, std::optional<long> links, std::optional<long> copies, bool floating_base) {
        SceneOptions options;
        options.variant = std::move(body), options.links = links, options.copies = copies, options.floating_base = floating_base;
        return load_scene_file(path, options);
      },
      py::arg("path"), py::kw_only(), py::arg("body") = py::none(), py::arg("links") = py::none(), py::arg("copies") = py::none(),
      py::arg("floating_base") = false,
      "Loads a scene file: limber's JSON, MuJoCo's MJCF (.xml) or a URDF robot (.urdf), with `limber run`'s scene flags: body (a "
      "variant: the humanoid's thin, medium, wide), links (a chain or tree generator's), copies (side by side), floating_base (a "
      "URDF robot's root floats). Raises ModelError naming the file and field (a name that is not UTF-8 text too).");
}

// Construction and what identifies the World (limber.World, in limber/__init__.py, wraps the
// constructor with keyword options).
void bind_identity(py::class_<LockedWorld>& bound, WorldMethods& world) {
  bound.def(py::init(&world_with_options), py::arg("scene"), py::arg("method"), py::arg("options"),
            "A World of a copy of `scene` under `method` (limber run's --method) with `options`, a dict of limber run's flags");
  world.def_property_readonly("time", &World::time, "s")
      .def_property_readonly("body_names", [](const World& w) {
        std::vector<std::string> names;
        for (const BodyId id : w.bodies()) names.push_back(w.body_description(id).name);
        return names;
      });
  // The name it was made with: set once, so no call can make it disagree with the World.
  bound.def_property_readonly("method", &LockedWorld::method, "limber run's --method: 'weighted', 'springs-implicit', ...");
}

// The arrays a bulk read-out fills: `out`'s pair, each a writeable C-contiguous float64 array of
// shape (rows, columns[k]) (ValueError naming it otherwise), or new ones when `out` is None.
std::array<py::array, 2> out_arrays(const py::object& out, const char* call, const std::array<const char*, 2>& names, std::size_t rows,
                                    const std::array<py::ssize_t, 2>& columns) {
  const auto shape = [&](std::size_t k) { return "(" + std::to_string(rows) + ", " + std::to_string(columns[k]) + ")"; };
  if (out.is_none()) return {Array({static_cast<py::ssize_t>(rows), columns[0]}), Array({static_cast<py::ssize_t>(rows), columns[1]})};
  if (!py::isinstance<py::tuple>(out) || py::len(out) != 2) {
    throw WorldError(std::string(call) + ": out must be a tuple (" + names[0] + " " + shape(0) + ", " + names[1] + " " + shape(1) +
                          ") of float64 arrays");
  }
  const auto take = [&](std::size_t k) {
    const py::handle given = out.cast<py::tuple>()[k];
    const auto refuse = [&](const std::string& got) {
      throw WorldError(std::string(call) + ": out[" + std::to_string(k) + "] (" + names[k] +
                            ") must be a writeable C-contiguous float64 array of shape " + shape(k) + ", got " + got);
    };
    if (!py::isinstance<py::array>(given)) refuse(py::str(given.get_type().attr("__name__")));
    const py::array array = given.cast<py::array>();
    const bool contiguous = (array.flags() & py::array::c_style) != 0;
    if (!py::isinstance<Array>(array) || !contiguous || !array.writeable() || array.ndim() != 2 ||
        array.shape(0) != static_cast<py::ssize_t>(rows) || array.shape(1) != columns[k]) {
      refuse(std::string(py::str(array.dtype())) + " of shape " + std::string(py::str(given.attr("shape"))) +
             (contiguous ? "" : ", not C-contiguous") + (array.writeable() ? "" : ", read-only"));
    }
    return array;
  };
  return {take(0), take(1)};
}

}  // namespace

namespace limber::python {

std::array<py::array, 2> pose_arrays(const World& w, const py::object& out) {
  return out_arrays(out, "poses", {"positions", "orientations"}, w.model().bodies.size(), {3, 4});
}

void fill_poses(const World& w, std::array<py::array, 2>& arrays) {
  thread_local std::vector<Pose> poses;  // kept between calls: a read into `out` allocates nothing
  poses.resize(w.model().bodies.size());
  w.poses(poses);
  double* position = static_cast<double*>(arrays[0].mutable_data());
  double* orientation = static_cast<double*>(arrays[1].mutable_data());
  for (std::size_t r = 0; r < poses.size(); ++r) {
    const Eigen::Quaterniond& q = poses[r].orientation;
    put(position + 3 * r, poses[r].position);
    double* row = orientation + 4 * r;
    row[0] = q.w(), row[1] = q.x(), row[2] = q.y(), row[3] = q.z();
  }
}

py::object read_poses(const World& w, const py::object& out) {
  std::array<py::array, 2> arrays = pose_arrays(w, out);
  fill_poses(w, arrays);
  return out.is_none() ? py::object(py::make_tuple(arrays[0], arrays[1])) : out;
}

}  // namespace limber::python

namespace {

// The bodies' state as arrays, and the observers.
void bind_read_outs(WorldMethods& world) {
  world.def(
          "poses", &read_poses,
          py::arg("out") = py::none(),
          "(positions N×3 m, orientations N×4 w x y z): each body frame's origin and rotation (body → world). With out=(positions, "
          "orientations), preallocated C-contiguous float64 arrays of those shapes, fills and returns them, allocating nothing; "
          "ValueError naming the argument otherwise.")
      .def(
          "motions", [](const World& w, const py::object& out) -> py::object {
            thread_local std::vector<Motion> motions;
            motions.resize(w.model().bodies.size());
            w.motions(motions);
            std::array<py::array, 2> arrays = out_arrays(out, "motions", {"linear", "angular"}, motions.size(), {3, 3});
            double* linear = static_cast<double*>(arrays[0].mutable_data());
            double* angular = static_cast<double*>(arrays[1].mutable_data());
            for (std::size_t r = 0; r < motions.size(); ++r) put(linear + 3 * r, motions[r].linear), put(angular + 3 * r, motions[r].angular);
            return out.is_none() ? py::object(py::make_tuple(arrays[0], arrays[1])) : out;
          },
          py::arg("out") = py::none(),
          "(linear N×3 m/s of each body frame's origin, angular N×3 rad/s), world; out= as poses()'s")
      .def("observe", [](const World& w) { return observation(w, w.observe()); },
           "energy (J), momentum (kg·m/s), joint gaps (relative to link length; 'widest_joint' names the joint of the largest, or "
           "None), limits (rad) and the deepest penetration now (m; 'penetration' names it: 'shin into the ground', or 'nothing') "
           "as a dict");
}

// Loads over the next step, and the actuators' controls.
void bind_loads(WorldMethods& world) {
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
void bind_joint_space(WorldMethods& world) {
  world.def("joint_space_names", &World::joint_space_names, "per velocity coordinate (nv): 'torso.wx', 'knee', ...")
      .def("joint_position_names", &World::joint_position_names, "per position coordinate (nq): 'torso.x', 'torso.qw', 'knee', ...")
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

namespace {

// Registers limber.<name>, a ValueError, raised for a C++ E with its what() (register_exception's
// translation, but a message quoting bytes that are not UTF-8, a name from a file, is decoded with
// them escaped instead of turning into a UnicodeDecodeError).
template <typename E>
void register_error(py::module_& m, const char* name) {
  static py::exception<E> type(m, name, PyExc_ValueError);  // one module, one class: as register_exception keeps it
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const E& error) {
      PyErr_SetObject(type.ptr(), text(error.what()).ptr());
    }
  });
}

}  // namespace

PYBIND11_MODULE(_limber, m) {
  m.doc() = "limber: articulated bodies with distributed mass (https://github.com/…/limber; README.md)";
  register_error<ModelError>(m, "ModelError");
  register_error<WorldError>(m, "WorldError");
  register_error<OptionError>(m, "OptionError");
  m.attr("methods") = std::vector<std::string>{"weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"};
  bind_scene(m);
  bind_generators(m);
  bind_handles(m);
  py::class_<LockedWorld> bound(m, "World", "One scene under one method, stepped and read (kernel/world/world.hpp).");
  WorldMethods world(bound);
  bind_identity(bound, world);
  bind_running(world);
  bind_read_outs(world);
  bind_loads(world);
  bind_joint_space(world);
  bind_edits(world);
  bind_report_calls(world);
}
