// World's reports from Python: the last step's report, the limbs as collision sees them, one
// body's pose, motion and description, and the joints' drives (set and read).
#include <optional>
#include <string>
#include <vector>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "tools/python/module.hpp"

namespace limber::python {
namespace {

const char* stop_name(RelaxationStop stop) {
  switch (stop) {
    case RelaxationStop::iterations: return "iterations";
    case RelaxationStop::tolerance: return "tolerance";
    case RelaxationStop::budget: return "budget";
    case RelaxationStop::idle: return "idle";
  }
  return "unknown";
}

py::dict profile_dict(const StepProfile& p) {
  py::dict out;
  out["integrate"] = p.integrate, out["detect"] = p.detect, out["colour"] = p.colour, out["relax"] = p.relax;
  out["velocity"] = p.velocity, out["restitution"] = p.restitution, out["sleep"] = p.sleep, out["step"] = p.step;
  out["substeps"] = p.substeps, out["position_sweeps"] = p.position_sweeps, out["velocity_sweeps"] = p.velocity_sweeps;
  out["contact_rows"] = p.contact_rows, out["contact_colours"] = p.contact_colours, out["candidate_pairs"] = p.candidate_pairs;
  out["limb_searches"] = p.limb_searches, out["contacts"] = p.contacts, out["tree_solves"] = p.tree_solves;
  out["tree_newton_steps"] = p.tree_newton_steps, out["tree_capped"] = p.tree_capped;
  out["tree_factors"] = p.tree_factors, out["tree_inverse_diagonals"] = p.tree_inverse_diagonals;
  out["tree_substitutions"] = p.tree_substitutions, out["tree_path_solves"] = p.tree_path_solves;
  out["tree_lane_slots"] = p.tree_lane_slots;
  out["tree_staging"] = p.tree_staging, out["tree_elimination"] = p.tree_elimination;
  out["tree_moves"] = p.tree_moves, out["tree_contacts"] = p.tree_contacts;
  return out;
}

py::dict report_dict(const StepReport& r) {
  py::dict out;
  out["status"] = name(r.status), out["contacts"] = r.contacts;
  out["stop"] = stop_name(r.stop), out["iterations"] = r.iterations, out["largest_correction"] = r.largest_correction;
  out["substeps"] = r.substeps, out["fallbacks"] = r.fallbacks;
  out["linear_solver_iterations"] = r.linear_solver_iterations, out["linear_solver_error"] = r.linear_solver_error;
  out["constraint_error"] = r.constraint_error, out["angular_error"] = r.angular_error;
  out["profile"] = profile_dict(r.profile);
  return out;
}

py::dict drive_dict(const JointDrive& d) {
  py::dict out;
  out["stiffness"] = d.stiffness, out["damping"] = d.damping, out["target"] = d.target, out["target_velocity"] = d.target_velocity;
  out["target_rotation"] = numbers(d.target_rotation), out["target_angular_velocity"] = numbers(d.target_angular_velocity);
  return out;
}

void bind_reports(WorldMethods& world) {
  world
      .def("last_report", [](const World& w) { return report_dict(w.last_report()); },
           "The last step's report as a dict, whatever the method (a field another method fills stays 0): status (step()'s), "
           "contacts; particles: stop ('iterations', 'tolerance', 'budget', 'idle'), iterations (sweeps), largest_correction (m), "
           "substeps, fallbacks; springs: linear_solver_iterations, linear_solver_error (relative residual); Lagrange: "
           "constraint_error (m), angular_error (~rad); profile: a dict of the stages' seconds and counts (all 0 unless the method's "
           "profile option is on; kernel/model/step_status.hpp's StepProfile).")
      .def(
          "segments", [](const World& w) {
            std::vector<LimbSegment> segments;
            w.segments(segments);
            Array radii(static_cast<py::ssize_t>(segments.size()));
            for (std::size_t k = 0; k < segments.size(); ++k) radii.mutable_at(static_cast<py::ssize_t>(k)) = segments[k].radius;
            return py::make_tuple(rows(segments.size(), 3, [&](std::size_t k, double* row) { put(row, segments[k].head); }),
                                  rows(segments.size(), 3, [&](std::size_t k, double* row) { put(row, segments[k].tail); }), radii);
          },
          "(heads S×3 m, tails S×3 m, radii S m): each body's limb as collision sees it now, then each ball's (head = tail = its "
          "centre), S = bodies + balls")
      .def(
          "pose", [](const World& w, const std::string& body) {
            const Pose pose = w.pose(w.body(body));
            const Eigen::Quaterniond& q = pose.orientation;
            return py::make_tuple(numbers(pose.position), numbers({q.w(), q.x(), q.y(), q.z()}));
          },
          py::arg("body"), "(position 3 m, orientation 4 w x y z) of the body frame: the row of poses() for this body")
      .def(
          "motion", [](const World& w, const std::string& body) {
            const Motion motion = w.motion(w.body(body));
            return py::make_tuple(numbers(motion.linear), numbers(motion.angular));
          },
          py::arg("body"), "(linear 3 m/s of the body frame's origin, angular 3 rad/s), world: the row of motions() for this body")
      .def("body_description", [](const World& w, const std::string& body) { return body_dict(w.body_description(w.body(body))); },
           py::arg("body"),
           "The body's Model entry as a scene file's \"bodies\" entry (a dict; initial pose and velocity, shape, mass): what add_body "
           "takes");
}

void bind_drives(WorldMethods& world) {
  world
      .def(
          "set_joint_drive", [](World& w, const std::string& joint, py::none) { w.set_joint_drive(w.joint(joint), std::nullopt); },
          py::arg("joint"), py::arg("drive"), "set_joint_drive(joint, None) removes the joint's drive (a recompile)")
      .def(
          "set_joint_drive", [](World& w, const std::string& joint, double stiffness, double damping, double target, double target_velocity,
                                const std::optional<Array>& rotation, const std::optional<Array>& angular_velocity) {
            const JointDrive drive{stiffness, damping, target, target_velocity, vector3_or(rotation, Eigen::Vector3d::Zero(), "target_rotation"),
                                   vector3_or(angular_velocity, Eigen::Vector3d::Zero(), "target_angular_velocity")};
            w.set_joint_drive(w.joint(joint), drive);
          },
          py::arg("joint"), py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0, py::arg("target") = 0.0,
          py::arg("target_velocity") = 0.0, py::arg("target_rotation") = py::none(), py::arg("target_angular_velocity") = py::none(),
          "Sets the joint's PD drive from the next step on (model.hpp's JointDrive; each field 0 when not given): stiffness "
          "N·m/rad (N/m prismatic) and damping N·m·s/rad (N·s/m), ≥ 0; revolute: target (rad) and target_velocity (rad/s); "
          "prismatic: m, m/s; spherical: target_rotation (3, rotation vector from rest, rad, world axes at rest, |·| < π) and "
          "target_angular_velocity (3, rad/s). set_joint_drive(j, **world.joint_drive(j)) sets it again. Raises WorldError on a "
          "bad value or a joint type without drives, nothing changed.")
      .def(
          "joint_drive", [](const World& w, const std::string& joint) -> py::object {
            const std::optional<JointDrive> drive = w.joint_drive(w.joint(joint));
            return drive ? py::object(drive_dict(*drive)) : py::object(py::none());
          },
          py::arg("joint"), "The joint's drive now as a dict of set_joint_drive's keywords, or None; limp once drives_released")
      .def_property_readonly("drives_released", &World::drives_released,
                             "Whether a ball's impact has made the drives limp (settings.release_drives_on_impact)");
}

}  // namespace

void bind_report_calls(WorldMethods& world) {
  bind_reports(world);
  bind_drives(world);
}

}  // namespace limber::python
