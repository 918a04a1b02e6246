#include "limber/kernel/featherstone/articulated_tree.hpp"

#include <cmath>
#include <string>

#include <Eigen/Eigenvalues>

#include "limber/kernel/model/checks.hpp"

namespace limber {

int joint_position_count(ArticulatedJoint type) {
  switch (type) {
    case ArticulatedJoint::revolute:
    case ArticulatedJoint::prismatic: return 1;
    case ArticulatedJoint::spherical: return 4;
    case ArticulatedJoint::fixed: return 0;
    case ArticulatedJoint::floating: return 7;
  }
  return 0;
}

const char* articulated_joint_name(ArticulatedJoint type) {
  switch (type) {
    case ArticulatedJoint::revolute: return "revolute";
    case ArticulatedJoint::prismatic: return "prismatic";
    case ArticulatedJoint::spherical: return "spherical";
    case ArticulatedJoint::fixed: return "fixed";
    case ArticulatedJoint::floating: return "floating";
  }
  return "unknown";
}

void validate_articulated_body(const ArticulatedBody& body, int index) {
  // "bodies[3] ("forearm").<field>", formatted only on failure.
  const auto path = [&](const char* field) {
    return [&body, index, field] {
      std::string text = checks::indexed("bodies", static_cast<std::size_t>(index));
      if (!body.name.empty()) text += " (\"" + body.name + "\")";
      return text + "." + field;
    };
  };
  using checks::fail;
  using checks::format_number;

  if (body.parent < -1 || body.parent >= index) {
    fail(path("parent"), "must be -1 (the world) or an earlier body (< " + std::to_string(index) + "), got " +
                             std::to_string(body.parent));
  }
  switch (body.joint) {
    case ArticulatedJoint::revolute:
    case ArticulatedJoint::prismatic: checks::require_unit(body.joint_axis, path("joint_axis")); break;
    case ArticulatedJoint::spherical:
    case ArticulatedJoint::fixed:
    case ArticulatedJoint::floating: break;
    default: fail(path("joint"), "unknown joint type " + std::to_string(static_cast<int>(body.joint)));
  }

  const Eigen::Matrix3d& rotation = body.tree_transform.rotation;
  if (!rotation.allFinite()) fail(path("tree_transform.rotation"), "must be finite");
  checks::require_finite(body.tree_transform.translation, path("tree_transform.translation"));
  const double orthogonality = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm();
  if (!(orthogonality <= 1e-9) || !(rotation.determinant() > 0)) {
    fail(path("tree_transform.rotation"), "must be a rotation matrix (orthonormal, det +1); |E^T E - 1| = " +
                                              format_number(orthogonality) + ", det = " + format_number(rotation.determinant()));
  }

  checks::require_non_negative(body.armature, path("armature"));
  if (body.armature > 0 && body.joint != ArticulatedJoint::revolute && body.joint != ArticulatedJoint::prismatic) {
    fail(path("armature"), "is for revolute and prismatic joints");
  }
  const SpatialInertia& inertia = body.inertia;
  if (body.joint_frame) {
    if (inertia.mass != 0 || !inertia.first_moment.isZero() || !inertia.rotational_inertia.isZero()) {
      fail(path("inertia"), "must be zero: a joint frame is massless");
    }
    return;
  }
  checks::require_positive(inertia.mass, path("inertia.mass"));
  checks::require_finite(inertia.first_moment, path("inertia.first_moment"));
  if (!inertia.rotational_inertia.allFinite()) fail(path("inertia.rotational_inertia"), "must be finite");
  const Eigen::Matrix3d about_centre = inertia.inertia_about_centre_of_mass();
  const double scale = about_centre.norm();
  if (!((about_centre - about_centre.transpose()).norm() <= 1e-9 * scale)) {
    fail(path("inertia.rotational_inertia"), "must be symmetric");
  }
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(about_centre, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(moments[0] > 0)) {
    fail(path("inertia.rotational_inertia"), "must be positive definite about the centre of mass, smallest principal moment " +
                                                 format_number(moments[0]) + " kg m^2");
  }
  if (!(moments[0] + moments[1] >= moments[2] * (1 - 1e-9))) {
    fail(path("inertia.rotational_inertia"), "principal moments " + format_number(moments[0]) + ", " + format_number(moments[1]) +
                                                 ", " + format_number(moments[2]) +
                                                 " kg m^2 break the triangle inequality (no mass distribution has them)");
  }
}

void validate_articulated_bodies(const std::vector<ArticulatedBody>& bodies) {
  for (std::size_t i = 0; i < bodies.size(); ++i) validate_articulated_body(bodies[i], static_cast<int>(i));
}

ArticulatedTree::ArticulatedTree(std::vector<ArticulatedBody> bodies) {
  bodies_.reserve(bodies.size());
  position_offset_.reserve(bodies.size());
  velocity_offset_.reserve(bodies.size());
  for (ArticulatedBody& body : bodies) add_body(std::move(body));
}

int ArticulatedTree::add_body(ArticulatedBody body) {
  const int index = body_count();
  validate_articulated_body(body, index);
  position_offset_.push_back(position_count_);
  velocity_offset_.push_back(velocity_count_);
  position_count_ += joint_position_count(body.joint);
  velocity_count_ += joint_velocity_count(body.joint);
  bodies_.push_back(std::move(body));
  return index;
}

Eigen::VectorXd ArticulatedTree::neutral_positions() const {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(position_count_);
  for (int i = 0; i < body_count(); ++i) {
    const int offset = position_offset(i);
    if (body(i).joint == ArticulatedJoint::spherical) q[offset] = 1;      // (w, x, y, z) = (1, 0, 0, 0)
    if (body(i).joint == ArticulatedJoint::floating) q[offset + 3] = 1;   // after the position
  }
  return q;
}

}  // namespace limber
