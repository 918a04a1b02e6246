// World's edits from Python: structure (bodies, joints, models, colliders, balls), held points,
// teleports and sleep. Bodies, joints and colliders are addressed by name, as the loads are;
// balls and pins, which have no names, by the handles limber.Ball and limber.Pin (world.hpp's
// BallId and PinId: a removed one, or another World's, raises WorldError). Descriptions are dicts
// in the scene file's terms, read by the scene reader (scene_elements.cpp).
#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "tools/python/module.hpp"

namespace limber::python {
namespace {

// The one element a minimal scene of `section`: [description] holds, or ModelError.
py::dict only(const char* section, const py::dict& description) {
  py::dict sections;
  sections[section] = py::make_tuple(description);
  return sections;
}

// add_joint's description read with the bodies it names (their World descriptions, so "head" and
// "tail" anchors have the shapes' lengths), then turned to the World's body indices.
Joint joint_from(const World& world, const py::dict& description) {
  std::vector<std::string> named;
  py::list bodies;
  for (const char* end : {"inboard", "outboard"}) {
    if (!description.contains(end) || !py::isinstance<py::str>(description[end])) continue;  // the reader names the problem
    const std::string name = description[end].cast<std::string>();
    const int b = world.model().find_body(name);
    if (b < 0 || std::find(named.begin(), named.end(), name) != named.end()) continue;
    named.push_back(name), bodies.append(body_dict(world.model().bodies[static_cast<std::size_t>(b)]));
  }
  py::dict sections = only("joints", description);
  sections["bodies"] = bodies;
  Joint joint = scene_of("add_joint", sections).model.joints.at(0);
  const auto world_index = [&](int b) { return b == kWorld ? kWorld : world.model().find_body(named[static_cast<std::size_t>(b)]); };
  joint.inboard = world_index(joint.inboard), joint.outboard = world_index(joint.outboard);
  return joint;
}

// `edit()`, with a ModelError the World raises (a check of the whole edited Model: a name another
// body has) led by the call's name, as the scene reader's are.
template <typename Edit>
auto named(const char* call, Edit&& edit) {
  try {
    return edit();
  } catch (const ModelError& error) {
    throw ModelError(std::string(call) + ": " + error.what());
  }
}

template <typename Id>
void bind_handle(py::module_& m, const char* name, const char* doc) {
  py::class_<Id>(m, name, doc)
      .def("__eq__", [](const Id& a, const Id& b) { return a == b; }, py::is_operator())
      .def("__hash__", [](const Id& id) { return std::hash<std::uint64_t>{}((std::uint64_t{id.slot} << 32) ^ id.generation ^ (std::uint64_t{id.world} << 48)); })
      .def("__repr__", [name](const Id& id) {
        return "limber." + std::string(name) + "(slot=" + std::to_string(id.slot) + ", generation=" + std::to_string(id.generation) + ")";
      });
}

void bind_bodies_and_joints(WorldMethods& world) {
  world
      .def(
          "add_body", [](World& w, const py::dict& description) {
            const Body body = scene_of("add_body", only("bodies", description)).model.bodies.at(0);
            return named("add_body", [&] { return w.body_description(w.add_body(body)).name; });
          },
          py::arg("description"),
          "Adds a body described as a scene file's \"bodies\" entry (a dict: name, shape, mass or density or point_masses, position "
          "m, axis, ...; kernel/scene/scene_file.hpp), at that pose and velocity; every other body keeps its state (under "
          "settings.sleep.start_asleep a body added at rest starts asleep: wake() it). Returns its name. "
          "Raises ModelError naming the field (\"add_body: bodies[0].mass: must be > 0, got -1\"), nothing changed; also for a "
          "description nesting dicts and lists deeper than 64 levels or containing itself (as add_joint, add_collider, add_ball).")
      .def(
          "add_joint", [](World& w, const py::dict& description) {
            const Joint joint = joint_from(w, description);
            return named("add_joint", [&] { return w.model().joints[w.index(w.add_joint(joint))].name; });
          },
          py::arg("description"),
          "Adds a joint described as a scene file's \"joints\" entry (name, type, inboard and outboard by body name or \"world\", "
          "anchors \"head\", \"tail\" or [x, y, z] m, ...). The anchors are read against the bodies' initial poses, as the scene's. "
          "Returns its name. Raises ModelError naming the field (\"add_joint: joints[0].outboard: no body named ...\").")
      .def("remove_body", [](World& w, const std::string& body) { w.remove_body(w.body(body)); }, py::arg("body"),
           "Removes the body and its joints; the others keep their state")
      .def("remove_joint", [](World& w, const std::string& joint) { w.remove_joint(w.joint(joint)); }, py::arg("joint"))
      .def(
          "add_model", [](World& w, const Scene& scene, const std::string& prefix, const std::optional<Array>& offset) {
            std::vector<std::string> names;
            const Eigen::Vector3d shift = vector3_or(offset, Eigen::Vector3d::Zero(), "offset");
            for (const BodyId id : named("add_model", [&] { return w.add_model(scene.model, prefix, shift); })) {
              names.push_back(w.body_description(id).name);
            }
            return names;
          },
          py::arg("scene"), py::arg("prefix"), py::arg("offset") = py::none(),
          "Adds every body, joint and gear of `scene` (a limber.Scene), names led by `prefix`, moved by `offset` (3, m). Returns "
          "the new bodies' names in the scene's order.")
      .def_property_readonly("joint_names", [](const World& w) {
        std::vector<std::string> names;
        for (const Joint& joint : w.model().joints) names.push_back(joint.name);
        return names;
      });
}

void bind_colliders_and_balls(WorldMethods& world) {
  world
      .def(
          "add_collider", [](World& w, const py::dict& description) {
            const StaticCollider collider = scene_of("add_collider", only("colliders", description)).model.colliders.at(0);
            named("add_collider", [&] { return w.add_collider(collider); });
            return collider.name;
          },
          py::arg("description"),
          "Adds static level geometry described as a scene file's \"colliders\" entry (name, type \"box\", \"capsule\", \"mesh\" or "
          "\"stairs\", ...). Returns its name. Raises ModelError naming the field (\"add_collider: colliders[0].half_extents: ...\").")
      .def("remove_collider", [](World& w, const std::string& collider) { w.remove_collider(w.collider(collider)); }, py::arg("collider"))
      .def_property_readonly("collider_names", [](const World& w) {
        std::vector<std::string> names;
        for (const StaticCollider& collider : w.model().colliders) names.push_back(collider.name);
        return names;
      })
      .def(
          "add_ball", [](World& w, const py::dict& description) {
            const Ball ball = scene_of("add_ball", only("balls", description)).model.balls.at(0);
            return named("add_ball", [&] { return w.add_ball(ball); });
          },
          py::arg("description"),
          "Throws a ball described as a scene file's \"ball\" (radius m, mass kg, restitution, position m, speed m/s, direction). "
          "Returns its limber.Ball. Raises ModelError naming the field (\"add_ball: balls[0].radius: ...\").")
      .def("remove_ball", &World::remove_ball, py::arg("ball"))
      .def("balls", &World::balls, "Every ball's limber.Ball, in the scene's order")
      .def(
          "ball", [](const World& w, BallId ball) {
            const BallMotion motion = w.ball(ball);
            return py::make_tuple(numbers(motion.position), numbers(motion.velocity));
          },
          py::arg("ball"), "(position 3 m, velocity 3 m/s) of the ball's centre, world");
}

void bind_holds(WorldMethods& world) {
  world
      .def(
          "pin", [](World& w, const std::string& body, const Array& local_point) {
            const Eigen::Vector3d point = vector3(local_point, "local_point");
            return named("pin", [&] { return w.pin(w.body(body), point); });
          },
          py::arg("body"), py::arg("local_point"),
          "Holds the body's point `local_point` (3, m, its body frame: origin at the centre, z along its axis) where it is now, by a "
          "spherical joint to the world. Returns a limber.Pin. Featherstone raises WorldError (its tree cannot take it); the "
          "particle methods hold only a limb's head or tail (ModelError otherwise).")
      .def("unpin", &World::unpin, py::arg("pin"))
      .def(
          "move_pin", [](World& w, PinId pin, const Array& target) { w.move_pin(pin, vector3(target, "target")); }, py::arg("pin"),
          py::arg("target"), "Moves the held point's world anchor to `target` (3, m) over the next step")
      .def("pin_position", [](const World& w, PinId pin) { return numbers(w.pin_position(pin)); }, py::arg("pin"),
           "Where the held point's world anchor is (3, m)");
}

void bind_teleports_and_sleep(WorldMethods& world) {
  world
      .def(
          "teleport", [](World& w, const std::string& body, const Array& position, const Array& orientation, const std::optional<Array>& linear,
                         const std::optional<Array>& angular) {
            const Pose pose{vector3(position, "position"), quaternion(orientation, "orientation")};
            const Motion motion{vector3_or(linear, Eigen::Vector3d::Zero(), "linear_velocity"),
                                vector3_or(angular, Eigen::Vector3d::Zero(), "angular_velocity")};
            w.teleport(w.body(body), pose, motion);
          },
          py::arg("body"), py::arg("position"), py::arg("orientation"), py::arg("linear_velocity") = py::none(),
          py::arg("angular_velocity") = py::none(),
          "Sets the body frame's position (3, m), orientation (4, w x y z, unit within 1e-3; normalized), the origin's velocity (3, "
          "m/s; default 0) and the angular velocity (3, rad/s, world; default 0). Featherstone moves only a floating root. Raises "
          "WorldError (nothing changed) on a non-finite value or a quaternion far from unit.")
      .def("wake", [](World& w, const std::string& body) { w.wake(w.body(body)); }, py::arg("body"), "Wakes the body's island")
      .def("wake_all", &World::wake_all)
      .def("sleep", [](World& w, const std::string& body) { w.sleep(w.body(body)); }, py::arg("body"),
           "Puts the body's island to sleep now, its velocities zeroed; a contact, a load or wake() wakes it")
      .def("sleeping", [](const World& w, const std::string& body) { return w.sleeping(w.body(body)); }, py::arg("body"));
}

}  // namespace

Eigen::Quaterniond quaternion(const Array& in, const char* what) {
  if (in.ndim() != 1 || in.shape(0) != 4) throw WorldError(std::string(what) + ": expected 4 numbers (w, x, y, z)");
  return {in.at(0), in.at(1), in.at(2), in.at(3)};
}

void bind_handles(py::module_& m) {
  bind_handle<BallId>(m, "Ball", "A ball of a World (World.add_ball, World.balls): a handle, refused once the ball is removed");
  bind_handle<PinId>(m, "Pin", "A held point of a World (World.pin): a handle, refused once unpinned");
}

void bind_edits(WorldMethods& world) {
  bind_bodies_and_joints(world);
  bind_colliders_and_balls(world);
  bind_holds(world);
  bind_teleports_and_sleep(world);
}

}  // namespace limber::python
