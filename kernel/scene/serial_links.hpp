// Serial joints for the maximal-coordinate methods: each axis a revolute or prismatic joint, with
// a light virtual link between consecutive axes.
//
// Featherstone runs a serial joint exactly, its k − 1 joint frames massless (featherstone/README.md).
// A particle or rigid-body method needs a body between two axes, so the joint becomes a chain
//   inboard —axis 0→ link 0 —axis 1→ link 1 … link k−2 —axis k−1→ outboard,
// each link a cylinder that collides with nothing, of mass kVirtualLinkMassShare × the outboard's,
// taken out of the outboard (its mass properties scaled) so the total mass is the Model's. The
// error this leaves is O(share): tests/scene/serial_links_test.cpp measures it against Featherstone.
//
// Armature (MuJoCo's reflected rotor inertia, a term on the mass matrix's diagonal) stays on the
// expansion's joints for a method that applies it on the joint's rate (Lagrange: a compliant row,
// kernel/lagrange/README.md, exact: 0.43 mm off Featherstone's swing on two skew hinges after
// 0.5 s, within the virtual link's own 1.04 mm). For the particles it becomes a rotor carried by
// the body after the hinge: a solid disc's inertia, a about the axis and a/2 across it (a disc,
// so the body's tensor stays physical). On a hinge to the world it is MuJoCo's ½a·q̇² exactly;
// after other axes the disc turns with them too, and its a/2 across adds to their inertia (as a
// rotor under Lagrange the same swing was 0.069 m off, 0.157 m with no armature at all), and on
// a virtual link of 1 % of its body's mass it is 10³× the link's own inertia. The particles moved
// MuJoCo's humanoid's bodies of several hinges wrongly under their motors (bench/models.md), so
// they refuse an actuator on such an axis (MethodCapabilities::serial_actuators). A slide's
// armature has no such form and stays on the joint, for the method to refuse.
#pragma once

#include <cstdint>
#include <vector>

#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// Each virtual link's mass as a share of its serial joint's outboard body's mass.
inline constexpr double kVirtualLinkMassShare = 1e-2;

/// The expansion's joint of Model joint `joint`'s coordinate `axis`: axis 0 keeps the joint's
/// index, axes 1… follow `first_added_joint[joint]` (SerialExpansion below).
inline std::uint32_t joint_of_axis(const std::vector<std::uint32_t>& first_added_joint, std::size_t joint, int axis) {
  return axis == 0 ? static_cast<std::uint32_t>(joint) : first_added_joint[joint] + static_cast<std::uint32_t>(axis - 1);
}

/// A Model with its serial joints expanded (`model`), and where each axis went.
///
/// The Model's bodies and joints keep their indices: joint j's axis 0 is joint j of the
/// expansion (revolute or prismatic); its axes 1 … k−1 and its k − 1 links are appended after
/// the Model's joints and bodies, joint by joint. Names: "<joint>/<axis name>" for the joints
/// of axes 1…, "<joint>/link<i>" for the links; axis 0 keeps the joint's name. Each actuator
/// moves to its axis's joint.
struct SerialExpansion {
  Model model;
  /// Per Model joint: the expansion's joint of its axis 1 (axes 1… are consecutive); unused
  /// for a joint that is not serial.
  std::vector<std::uint32_t> first_added_joint;

  /// The expansion's joint of Model joint `joint`'s coordinate `axis` (0 for a joint that is not serial).
  std::uint32_t joint_of_axis(std::size_t joint, int axis) const { return limber::joint_of_axis(first_added_joint, joint, axis); }
};

/// What the expansion does with a hinge's armature: a rotor on the body after it (above), or
/// kept on the joint for the method to apply.
enum class Armature : std::uint8_t { as_rotor, on_joint };

/// Whether expand_serial_joints(model, armature) would change `model`: it has a serial joint,
/// or hinge armature to turn into rotors.
bool needs_serial_expansion(const Model& model, Armature armature = Armature::as_rotor);

/// `model` with every serial joint expanded into revolute and prismatic joints through virtual
/// links of `link_mass_share` of the outboard's mass each (in (0, 1/6)), each axis's armature on
/// its joint, and, `as_rotor`, every hinge's armature turned into a rotor on the body after it
/// (above). A Model with nothing to change comes back unchanged.
SerialExpansion expand_serial_joints(const Model& model, Armature armature = Armature::as_rotor,
                                     double link_mass_share = kVirtualLinkMassShare);

/// The Model joint that joint `expanded` of expand_serial_joints(model) comes from: itself for
/// the Model's own, else the serial joint whose axes 1… it is.
std::size_t model_joint_of(const Model& model, std::size_t expanded);

/// Extends `old_body_of_new` (Survivors::bodies: one entry per body of `fresh`) over the virtual
/// links of `fresh`'s expansion, for a recompile: each link continues the one at the same place
/// of the old Model's serial joint of the same name and axis count, else is new (−1).
std::vector<std::int64_t> with_virtual_links(const Model& old_model, const Model& fresh, std::vector<std::int64_t> old_body_of_new);

/// Where an actuator's joint force acts in an expansion, and how its coordinate is measured: each
/// joint coordinate's joint of the expansion, its bodies, its axis in the outboard body's frame
/// and the joint as the expansion has it. Each maximal-coordinate state keeps one
/// (apply_coordinate_force, coordinate_motion), empty without actuators.
struct CoordinateAxes {
  struct Axis {
    int inboard = kWorld, outboard = 0;            ///< the expansion's body indices
    Vector3 local_axis = Vector3::UnitX();         ///< unit, the outboard body's frame
    bool slide = false;                            ///< a prismatic joint's: a force, not a torque
    Joint joint;                                   ///< the expansion's joint (revolute or prismatic)
    JointFrame frame;                              ///< its rest frame (joint_coordinates.hpp)
  };
  std::vector<std::uint32_t> first_added_joint;   ///< SerialExpansion::first_added_joint
  std::vector<Axis> joints;                       ///< per joint of the expansion

  /// The axes of `expansion`'s joints, for the coordinates of the Model it expanded.
  static CoordinateAxes of(const SerialExpansion& expansion);
  /// The same for a Model that needed no expansion.
  static CoordinateAxes of(const Model& model);
};

/// Applies the joint force `amount` (N·m on a hinge, N on a slide) on Model joint `joint`'s
/// coordinate `axis` to a maximal-coordinate state: the pair ±amount·a of loads on the joint's
/// two bodies, a its axis as the outboard body holds it now. `State` has body_pose and
/// apply_body_load (kernel/methods/method_contract.hpp).
template <typename State>
void apply_coordinate_force(State& state, const CoordinateAxes& axes, std::size_t joint, int axis, double amount) {
  const CoordinateAxes::Axis& at = axes.joints[joint_of_axis(axes.first_added_joint, joint, axis)];
  const Vector3 along = amount * (body_pose(state, static_cast<std::size_t>(at.outboard)).orientation * at.local_axis);
  const Vector3 zero = Vector3::Zero();
  apply_body_load(state, static_cast<std::size_t>(at.outboard), at.slide ? along : zero, at.slide ? zero : along);
  if (at.inboard != kWorld) apply_body_load(state, static_cast<std::size_t>(at.inboard), at.slide ? Vector3(-along) : zero, at.slide ? zero : Vector3(-along));
}

/// Model joint `joint`'s coordinate `axis` in a maximal-coordinate state, from its bodies' poses
/// and motions (joint_coordinates.hpp): a hinge's angle and the outboard's angular velocity
/// relative to the inboard's along the hinge axis; a slide's travel and its rate, the outboard
/// anchor's velocity relative to the inboard's along the axis the inboard carries. `State` has
/// body_pose and body_motion (kernel/methods/method_contract.hpp).
template <typename State>
CoordinateMotion coordinate_motion(const State& state, const CoordinateAxes& axes, std::size_t joint, int axis) {
  const CoordinateAxes::Axis& at = axes.joints[joint_of_axis(axes.first_added_joint, joint, axis)];
  const auto pose_of = [&](int body) { return body == kWorld ? Pose{} : body_pose(state, static_cast<std::size_t>(body)); };
  const auto motion_of = [&](int body) { return body == kWorld ? Motion{} : body_motion(state, static_cast<std::size_t>(body)); };
  const Pose in = pose_of(at.inboard), out = pose_of(at.outboard);
  const Motion in_motion = motion_of(at.inboard), out_motion = motion_of(at.outboard);
  const JointCoordinates now = joint_coordinates(at.joint, at.frame, {in.orientation, in.position}, {out.orientation, out.position});
  if (!at.slide) return {now.angle, (out_motion.angular - in_motion.angular).dot(out.orientation * at.local_axis)};
  const Vector3 axis_now = in.orientation * at.frame.axis;  // the inboard carries a slide's axis
  const Vector3 p_in = in.position + in.orientation * at.joint.inboard_anchor, p_out = out.position + out.orientation * at.joint.outboard_anchor;
  const Vector3 v_in = in_motion.linear + in_motion.angular.cross(p_in - in.position);
  const Vector3 v_out = out_motion.linear + out_motion.angular.cross(p_out - out.position);
  return {now.slide, (v_out - v_in).dot(axis_now) + (p_out - p_in).dot(in_motion.angular.cross(axis_now))};
}

}  // namespace limber
