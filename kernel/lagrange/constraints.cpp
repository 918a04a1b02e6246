// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/lagrange/constraints.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "limber/kernel/rigid/anchor_jacobian.hpp"

namespace limber {
namespace {

// Two unit vectors perpendicular to unit `axis` and to each other.
std::array<Eigen::Vector3d, 2> perpendicular_pair(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d first = axis.unitOrthogonal();
  return {first, axis.cross(first)};
}

// A side of a constraint at state y: its rotation and centre (the world: identity, origin).
struct Side {
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

Side side(const RigidBodyState& y, std::int32_t body) {
  if (body < 0) return {};
  return {y.orientation[body], y.position[body]};
}

Eigen::Vector3d body_velocity(const std::vector<Eigen::Vector3d>& velocity, std::int32_t body) {
  return body >= 0 ? velocity[body] : Eigen::Vector3d::Zero();
}

// The world separation d = p_i − p_o of joint c and the world anchor points.
struct Anchors {
  Eigen::Vector3d inboard, outboard;
};

Anchors anchor_points(const JointAnchors& anchors, const ConstraintGeometry& geometry, const RigidBodyState& y, std::size_t c) {
  const std::int32_t i = anchors.inboard[c], o = anchors.outboard[c];
  return {i >= 0 ? Eigen::Vector3d(y.position[i] + geometry.inboard_lever[c]) : anchors.inboard_anchor[c],
          y.position[o] + geometry.outboard_lever[c]};
}

}  // namespace

ConstraintSet compile_constraints(const RigidScene& scene, const Model& model) {
  ConstraintSet set;
  const RigidBodyState& y = scene.bodies.state;
  // World vectors at the initial poses into a body's frame.
  const auto into = [&](std::int32_t body, const Eigen::Vector3d& world) -> Eigen::Vector3d {
    return body >= 0 ? Eigen::Vector3d(y.orientation[body].conjugate() * world) : world;
  };
  set.row_offset.push_back(0);
  for (const Joint& joint : model.joints) {
    const std::int32_t i = joint.inboard, o = joint.outboard;
    ConstraintRows rows;
    const auto angular_pair = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
      rows.inboard_direction[rows.angular_rows] = into(i, u);
      rows.outboard_direction[rows.angular_rows] = into(o, v);
      ++rows.angular_rows;
    };
    const auto keep_rotation = [&] {
      const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), yy = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
      angular_pair(x, yy), angular_pair(yy, z), angular_pair(z, x);
    };
    switch (joint.type) {
      case JointType::spherical: rows.point_rows = 3; break;
      case JointType::revolute: {
        rows.point_rows = 3;
        for (const Eigen::Vector3d& normal : perpendicular_pair(joint.axis)) angular_pair(normal, joint.axis);
        break;
      }
      case JointType::universal:
        rows.point_rows = 3;
        angular_pair(joint.axis, joint.second_axis);
        break;
      case JointType::fixed:
        rows.point_rows = 3;
        keep_rotation();
        break;
      case JointType::prismatic: {
        rows.slide_rows = 2;
        const auto normals = perpendicular_pair(joint.axis);
        rows.slide_normal = {into(i, normals[0]), into(i, normals[1])};
        keep_rotation();
        break;
      }
    }
    set.inboard.push_back(i), set.outboard.push_back(o), set.rows.push_back(rows);
    set.row_offset.push_back(set.row_offset.back() + rows.rows());
  }
  set.joint_count = model.joints.size();
  for (const Gear& gear : model.gears) {
    ConstraintRows rows;
    rows.gear = true;
    rows.ratio = gear.ratio;
    rows.inboard_direction[0] = into(gear.first, gear.first_axis);
    rows.outboard_direction[0] = into(gear.second, gear.second_axis);
    set.inboard.push_back(gear.first), set.outboard.push_back(gear.second), set.rows.push_back(rows);
    set.row_offset.push_back(set.row_offset.back() + 1);
  }
  return set;
}

void ConstraintGeometry::resize(const ConstraintSet& constraints) {
  inboard_lever.assign(constraints.joint_count, Eigen::Vector3d::Zero());
  outboard_lever.assign(constraints.joint_count, Eigen::Vector3d::Zero());
  inboard_jacobian.resize(constraints.size());
  outboard_jacobian.resize(constraints.size());
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    inboard_jacobian[c].setZero(constraints.rows[c].rows(), 6);
    outboard_jacobian[c].setZero(constraints.rows[c].rows(), 6);
  }
}

void update_constraint_geometry(const ConstraintSet& constraints, const JointAnchors& anchors, const RigidBodyState& y,
                                ConstraintGeometry& geometry) {
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    const ConstraintRows& rows = constraints.rows[c];
    const Side in = side(y, constraints.inboard[c]), out = side(y, constraints.outboard[c]);
    ConstraintBlock& inboard = geometry.inboard_jacobian[c];
    ConstraintBlock& outboard = geometry.outboard_jacobian[c];
    if (rows.gear) {
      inboard << Eigen::RowVector3d::Zero(), -rows.ratio * (in.orientation * rows.inboard_direction[0]).transpose();
      outboard << Eigen::RowVector3d::Zero(), (out.orientation * rows.outboard_direction[0]).transpose();
      continue;
    }
    const Eigen::Vector3d inboard_lever = anchors.inboard[c] >= 0 ? Eigen::Vector3d(in.orientation * anchors.inboard_anchor[c])
                                                                  : Eigen::Vector3d::Zero();
    const Eigen::Vector3d outboard_lever = out.orientation * anchors.outboard_anchor[c];
    geometry.inboard_lever[c] = inboard_lever, geometry.outboard_lever[c] = outboard_lever;
    int row = 0;
    if (rows.point_rows) {
      inboard.topRows<3>() = anchor_jacobian(inboard_lever);
      outboard.topRows<3>() = -anchor_jacobian(outboard_lever);
      row = 3;
    }
    for (int k = 0; k < rows.slide_rows; ++k, ++row) {
      const Eigen::Vector3d b = in.orientation * rows.slide_normal[k];
      const Eigen::Vector3d outboard_point = out.centre + outboard_lever;
      // Segment by segment: GCC 12 misreads the comma initializer of a Vector3d under AVX
      // (-Warray-bounds on an unaligned 4-wide load; bug 105593's family).
      inboard.row(row).head<3>() = b.transpose(), inboard.row(row).tail<3>() = (outboard_point - in.centre).cross(b).transpose();
      outboard.row(row).head<3>() = -b.transpose(), outboard.row(row).tail<3>() = -outboard_lever.cross(b).transpose();
    }
    for (int k = 0; k < rows.angular_rows; ++k, ++row) {
      const Eigen::Vector3d w = (in.orientation * rows.inboard_direction[k]).cross(out.orientation * rows.outboard_direction[k]);
      inboard.row(row) << Eigen::RowVector3d::Zero(), w.transpose();
      outboard.row(row) << Eigen::RowVector3d::Zero(), -w.transpose();
    }
  }
}

ConstraintVector constraint_error(const ConstraintSet& constraints, const JointAnchors& anchors, const RigidBodyState& y,
                                  std::size_t c) {
  const ConstraintRows& rows = constraints.rows[c];
  ConstraintVector error = ConstraintVector::Zero(rows.rows());
  if (rows.gear) return error;
  const Side in = side(y, constraints.inboard[c]), out = side(y, constraints.outboard[c]);
  const Eigen::Vector3d separation = joint_separation(anchors, y, c);
  int row = 0;
  if (rows.point_rows) error.head<3>() = separation, row = 3;
  for (int k = 0; k < rows.slide_rows; ++k) error(row++) = (in.orientation * rows.slide_normal[k]).dot(separation);
  for (int k = 0; k < rows.angular_rows; ++k) {
    error(row++) = (in.orientation * rows.inboard_direction[k]).dot(out.orientation * rows.outboard_direction[k]);
  }
  return error;
}

// Scalar loops: GCC 12 warns falsely (-Warray-bounds) on Eigen's vectorized reductions over
// fixed-capacity vectors.
double position_error(const ConstraintRows& rows, const ConstraintVector& error) {
  double squares = 0;
  for (int k = 0; k < rows.point_rows + rows.slide_rows; ++k) squares += error(k) * error(k);
  return std::sqrt(squares);
}

double angular_error(const ConstraintRows& rows, const ConstraintVector& error) {
  double largest = 0;
  for (int k = rows.point_rows + rows.slide_rows; k < rows.point_rows + rows.slide_rows + rows.angular_rows; ++k) {
    largest = std::max(largest, std::abs(error(k)));
  }
  return largest;
}

ConstraintVector constraint_rate(const ConstraintSet& constraints, const ConstraintGeometry& geometry,
                                 const std::vector<Eigen::Vector3d>& velocity, const std::vector<Eigen::Vector3d>& angular_velocity,
                                 std::size_t c) {
  const std::int32_t i = constraints.inboard[c], o = constraints.outboard[c];
  Eigen::Matrix<double, 6, 1> outboard_velocity;
  outboard_velocity << velocity[o], angular_velocity[o];
  ConstraintVector rate = geometry.outboard_jacobian[c] * outboard_velocity;
  if (i >= 0) {
    Eigen::Matrix<double, 6, 1> inboard_velocity;
    inboard_velocity << velocity[i], angular_velocity[i];
    rate += geometry.inboard_jacobian[c] * inboard_velocity;
  }
  return rate;
}

ConstraintVector velocity_product(const ConstraintSet& constraints, const JointAnchors& anchors, const ConstraintGeometry& geometry,
                                  const RigidBodyState& y, const std::vector<Eigen::Vector3d>& velocity,
                                  const std::vector<Eigen::Vector3d>& angular_velocity, std::size_t c) {
  const ConstraintRows& rows = constraints.rows[c];
  ConstraintVector product = ConstraintVector::Zero(rows.rows());
  if (rows.gear) return product;  // (ω×n)·ω = 0 on each side
  const std::int32_t i = constraints.inboard[c], o = constraints.outboard[c];
  const Side in = side(y, i), out = side(y, o);
  const Eigen::Vector3d w_i = body_velocity(angular_velocity, i), w_o = angular_velocity[o];
  const Eigen::Vector3d &r_i = geometry.inboard_lever[c], &r_o = geometry.outboard_lever[c];
  // The anchors' centripetal accelerations ω×(ω×r), whose difference is the point rows' J̇u.
  const Eigen::Vector3d centripetal = w_i.cross(w_i.cross(r_i)) - w_o.cross(w_o.cross(r_o));
  int row = 0;
  if (rows.point_rows) product.head<3>() = centripetal, row = 3;
  if (rows.slide_rows) {
    const Anchors points = anchor_points(anchors, geometry, y, c);
    const Eigen::Vector3d separation = points.inboard - points.outboard;
    const Eigen::Vector3d separation_rate =
        body_velocity(velocity, i) + w_i.cross(r_i) - velocity[o] - w_o.cross(r_o);
    for (int k = 0; k < rows.slide_rows; ++k, ++row) {
      // C = b·d with ḃ = ω_i×b: C̈ = b̈·d + 2ḃ·ḋ + b·d̈, less the terms in the accelerations.
      const Eigen::Vector3d b = in.orientation * rows.slide_normal[k];
      product(row) = w_i.cross(w_i.cross(b)).dot(separation) + 2 * w_i.cross(b).dot(separation_rate) + b.dot(centripetal);
    }
  }
  for (int k = 0; k < rows.angular_rows; ++k, ++row) {
    // C = u·v: Ċ = (u×v)·(ω_i − ω_o), so J̇u = d(u×v)/dt·(ω_i − ω_o).
    const Eigen::Vector3d u = in.orientation * rows.inboard_direction[k], v = out.orientation * rows.outboard_direction[k];
    product(row) = (w_i.cross(u).cross(v) + u.cross(w_o.cross(v))).dot(w_i - w_o);
  }
  return product;
}

}  // namespace limber
