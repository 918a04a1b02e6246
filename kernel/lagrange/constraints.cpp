#include "limber/kernel/lagrange/constraints.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "limber/kernel/model/joint_coordinates.hpp"
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

ConstraintSet compile_constraints(const RigidScene& scene, const Model& model, const std::vector<char>& servo_joints) {
  ConstraintSet set;
  const RigidBodyState& y = scene.bodies.state;
  // World vectors at the initial poses into a body's frame.
  const auto into = [&](std::int32_t body, const Eigen::Vector3d& world) -> Eigen::Vector3d {
    return body >= 0 ? Eigen::Vector3d(y.orientation[body].conjugate() * world) : world;
  };
  set.row_offset.push_back(0);
  for (std::size_t c = 0; c < model.joints.size(); ++c) {
    const Joint& joint = model.joints[c];
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
      case JointType::serial: break;  // refused by require_supported
      case JointType::prismatic: {
        rows.slide_rows = 2;
        const auto normals = perpendicular_pair(joint.axis);
        rows.slide_normal = {into(i, normals[0]), into(i, normals[1])};
        keep_rotation();
        break;
      }
    }
    rows.control_rows = static_cast<std::uint8_t>(control_row_count(joint, !servo_joints.empty() && servo_joints[c] != 0));
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


// --- Joint controls: limits, friction and drives (joint_controls.hpp) ---

int control_row_count(const Joint& joint, bool servo) {
  if (!has_joint_controls(joint) && !(joint.armature > 0) && !servo) return 0;  // armature, servos: revolute and prismatic only
  switch (joint.type) {
    case JointType::revolute:
    case JointType::prismatic: return 1;
    case JointType::spherical:
      if (joint.drive || joint.friction > 0) return 3;
      return (joint.limits.swing ? 1 : 0) + (joint.limits.twist ? 1 : 0);
    case JointType::universal: return joint.friction > 0 ? 2 : 0;
    case JointType::fixed:
    case JointType::serial: return 0;  // serial: refused by require_supported
  }
  return 0;
}

FramePose model_frame_pose(const RigidScene& scene, const RigidBodyState& y, std::int32_t body) {
  if (body < 0) return {};
  const auto b = static_cast<std::size_t>(body);
  const Eigen::Quaterniond orientation = y.orientation[b] * scene.shapes.principal_frame[b].conjugate();
  return {orientation, y.position[b] - orientation * scene.shapes.centre_offset[b]};
}

JointControlSet compile_joint_controls(const RigidScene& scene, const Model& model, const ConstraintSet& constraints) {
  JointControlSet set;
  const RigidBodyState& y = scene.bodies.state;
  const auto into = [&](std::int32_t body, const Eigen::Vector3d& world) -> Eigen::Vector3d {
    return body >= 0 ? Eigen::Vector3d(y.orientation[body].conjugate() * world) : world;
  };
  for (std::size_t k = 0; k < constraints.joint_count; ++k) {
    const ConstraintRows& rows = constraints.rows[k];
    if (rows.control_rows == 0) continue;
    const Joint& joint = model.joints[k];
    ControlledJoint controlled;
    controlled.joint = static_cast<std::uint32_t>(k);
    controlled.first_row = static_cast<std::uint32_t>(set.rows.size());
    controlled.row_offset = static_cast<std::uint8_t>(rows.equality_rows());
    controlled.count = rows.control_rows;
    controlled.type = joint.type;
    const std::int32_t i = joint.inboard, o = joint.outboard;
    const Eigen::Vector3d& outboard_axis = model.bodies[static_cast<std::size_t>(o)].axis;
    std::uint8_t directions[3] = {0, 1, 2};
    switch (joint.type) {
      case JointType::revolute:
        controlled.inboard_axis = into(i, joint.axis), controlled.outboard_axis = into(o, joint.axis);
        break;
      case JointType::prismatic: controlled.inboard_axis = into(i, joint.axis); break;
      case JointType::universal:
        controlled.inboard_axis = into(i, joint.axis), controlled.outboard_axis = into(o, joint.second_axis);
        break;
      case JointType::spherical:
        controlled.outboard_axis = into(o, outboard_axis);
        controlled.cone_axis = into(i, joint.limits.swing_axis.value_or(outboard_axis));
        if (rows.control_rows == 3) {
          if (joint.limits.swing) controlled.swing_row = 0;
          if (joint.limits.twist) controlled.twist_row = 2;
        } else {
          std::int8_t next = 0;
          if (joint.limits.swing) directions[next] = 0, controlled.swing_row = next++;
          if (joint.limits.twist) directions[next] = 2, controlled.twist_row = next++;
        }
        break;
      case JointType::fixed:
      case JointType::serial: break;
    }
    for (int r = 0; r < rows.control_rows; ++r) {
      ControlRow row;
      row.direction = directions[r];
      set.rows.push_back(row);
    }
    set.joints.push_back(controlled);
  }
  return set;
}

namespace {

double wrapped_angle(double angle) {
  constexpr double pi = std::numbers::pi;
  angle = std::fmod(angle + pi, 2 * pi);
  if (angle < 0) angle += 2 * pi;
  return angle - pi;
}

// The nearer limit of `range` from `value`: its side (+1 lower, −1 upper) and the gap (≥ 0 inside),
// divided by `scale` (the coordinate's rate per unit of the row's rate).
void set_nearer_limit(ControlRow& row, double value, const Range& range, double scale = 1) {
  if (value - range.min < range.max - value) {
    row.side = 1, row.gap = (value - range.min) / scale;
  } else {
    row.side = -1, row.gap = (range.max - value) / scale;
  }
}

// An angular row along unit-or-not `n` (rate n·(ω_o − ω_i)), with J̇u as if n turned with the
// inboard body.
void set_angular_row(ControlRow& row, const Eigen::Vector3d& n, const Eigen::Vector3d& w_i, const Eigen::Vector3d& w_o) {
  row.inboard_jacobian << 0, 0, 0, -n.transpose();
  row.outboard_jacobian << 0, 0, 0, n.transpose();
  row.rate = n.dot(w_o - w_i);
  row.velocity_product = (w_o - w_i).dot(w_i.cross(n));
}

// The rate of twist_gradient(a, a₀) (joint_coordinates.hpp), with a turning at ω_o and a₀ at ω_i.
Eigen::Vector3d twist_gradient_rate(const Eigen::Vector3d& a, const Eigen::Vector3d& rest, const Eigen::Vector3d& w_i,
                                    const Eigen::Vector3d& w_o) {
  const double denominator = 1 + a.dot(rest);
  if (!(denominator > 1e-9)) return w_o.cross(a);
  const Eigen::Vector3d a_rate = w_o.cross(a), rest_rate = w_i.cross(rest);
  return (a_rate + rest_rate) / denominator - (a + rest) * (a_rate.dot(rest) + a.dot(rest_rate)) / (denominator * denominator);
}

}  // namespace

void measure_joint_controls(const RigidScene& scene, const JointAnchors& anchors, const JointControls& controls,
                            const RigidBodyState& y, const std::vector<Eigen::Vector3d>& velocity,
                            const std::vector<Eigen::Vector3d>& angular_velocity, JointControlSet& set) {
  for (const ControlledJoint& controlled : set.joints) {
    const std::size_t k = controlled.joint;
    const Joint& joint = controls.joints[k];
    const JointFrame& frame = controls.frames[k];
    const std::int32_t i = anchors.inboard[k], o = anchors.outboard[k];
    const FramePose inboard = model_frame_pose(scene, y, i), outboard = model_frame_pose(scene, y, o);
    const JointCoordinates q = joint_coordinates(joint, frame, inboard, outboard);
    const Side in = side(y, i), out = side(y, o);
    const Eigen::Vector3d w_i = body_velocity(angular_velocity, i), w_o = angular_velocity[o];
    ControlRow* rows = &set.rows[controlled.first_row];
    for (int r = 0; r < controlled.count; ++r) {
      rows[r].side = 0, rows[r].gap = 0, rows[r].drive_error = 0, rows[r].target_rate = 0;
    }
    const JointLimits& limits = joint.limits;
    const JointDrive* drive = joint.drive ? &*joint.drive : nullptr;
    switch (controlled.type) {
      case JointType::revolute: {
        ControlRow& row = rows[0];
        const Eigen::Vector3d a = out.orientation * controlled.outboard_axis, rest = in.orientation * controlled.inboard_axis;
        set_angular_row(row, twist_gradient(a, rest), w_i, w_o);
        row.velocity_product = twist_gradient_rate(a, rest, w_i, w_o).dot(w_o - w_i);  // exact: w is the angle's rate
        if (limits.range) set_nearer_limit(row, q.angle, *limits.range);
        row.coordinate = q.angle;
        if (drive) row.drive_error = wrapped_angle(drive->target - q.angle), row.target_rate = drive->target_velocity;
        break;
      }
      case JointType::prismatic: {
        ControlRow& row = rows[0];
        const Eigen::Vector3d h = in.orientation * controlled.inboard_axis;
        const Eigen::Vector3d r_o = out.orientation * anchors.outboard_anchor[k];
        const Eigen::Vector3d r_i = i >= 0 ? Eigen::Vector3d(in.orientation * anchors.inboard_anchor[k]) : Eigen::Vector3d::Zero();
        const Eigen::Vector3d p_o = out.centre + r_o, p_i = i >= 0 ? Eigen::Vector3d(in.centre + r_i) : anchors.inboard_anchor[k];
        row.inboard_jacobian.head<3>() = -h.transpose(), row.inboard_jacobian.tail<3>() = -(p_o - in.centre).cross(h).transpose();
        row.outboard_jacobian.head<3>() = h.transpose(), row.outboard_jacobian.tail<3>() = r_o.cross(h).transpose();
        const Eigen::Vector3d v_po = velocity[o] + w_o.cross(r_o), v_pi = body_velocity(velocity, i) + w_i.cross(r_i);
        row.rate = h.dot(v_po - v_pi) + (p_o - p_i).dot(w_i.cross(h));  // h turns with the inboard body
        const Eigen::Vector3d centripetal = w_o.cross(w_o.cross(r_o)) - w_i.cross(w_i.cross(r_i));
        row.velocity_product = centripetal.dot(h) + 2 * (v_po - v_pi).dot(w_i.cross(h)) + (p_o - p_i).dot(w_i.cross(w_i.cross(h)));
        if (limits.range) set_nearer_limit(row, q.slide, *limits.range);
        row.coordinate = q.slide;
        if (drive) row.drive_error = drive->target - q.slide, row.target_rate = drive->target_velocity;
        break;
      }
      case JointType::universal: {
        const Eigen::Vector3d u = in.orientation * controlled.inboard_axis;
        const Eigen::Vector3d v = out.orientation * controlled.outboard_axis;
        const Eigen::Vector3d frame_vectors[2] = {u, (v - v.dot(u) * u).normalized()};
        for (int r = 0; r < controlled.count; ++r) set_angular_row(rows[r], frame_vectors[rows[r].direction], w_i, w_o);
        break;
      }
      case JointType::spherical: {
        const Eigen::Vector3d a = out.orientation * controlled.outboard_axis;
        const Eigen::Vector3d cone = in.orientation * controlled.cone_axis;  // the swing's and the twist's axis
        const Eigen::Vector3d t = twist_gradient(a, cone);
        // e₃ the twist direction (|t| ≥ 1), e₁ the swing direction c×a/|c×a| with a swing limit:
        // both angles are about c, so e₁ ⟂ e₃ (joint_controls.hpp).
        const double twist_scale = t.norm();
        const Eigen::Vector3d e3 = t / twist_scale;
        const Eigen::Vector3d across = cone.cross(a);
        const Eigen::Vector3d e1 = limits.swing && across.norm() > 1e-12 ? Eigen::Vector3d(across.normalized()) : e3.unitOrthogonal();
        const Eigen::Vector3d frame_vectors[3] = {e1, e3.cross(e1), e3};
        for (int r = 0; r < controlled.count; ++r) set_angular_row(rows[r], frame_vectors[rows[r].direction], w_i, w_o);
        const Eigen::Vector3d relative = w_o - w_i;
        if (controlled.swing_row >= 0) {
          ControlRow& row = rows[controlled.swing_row];
          row.side = -1, row.gap = *limits.swing - q.swing;
          // e₁ = m/|m|, m = c×a: its rate (I − e₁e₁ᵀ)·ṁ/|m| (0 where the cone axis and a meet).
          const double length = across.norm();
          if (length > 1e-12) {
            const Eigen::Vector3d m_rate = w_i.cross(cone).cross(a) + cone.cross(w_o.cross(a));
            row.velocity_product = ((m_rate - e1 * e1.dot(m_rate)) / length).dot(relative);
          }
        }
        if (controlled.twist_row >= 0) {
          ControlRow& row = rows[controlled.twist_row];
          set_nearer_limit(row, q.twist, *limits.twist, twist_scale);
          row.velocity_product = twist_gradient_rate(a, cone, w_i, w_o).dot(relative) / twist_scale;  // in the row's units
        }
        if (drive) {
          // The rotation still to go, E = D_target·D⁻¹ (inboard frame), as a rotation vector in world.
          Eigen::Quaterniond error = drive_target_rotation(*drive, frame) * Eigen::Quaterniond(rotation_quaternion(q.rotation)).conjugate();
          if (error.w() < 0) error.coeffs() = -error.coeffs();
          const Eigen::AngleAxisd turn(error.normalized());
          const Eigen::Vector3d error_vector = inboard.orientation * (turn.angle() * turn.axis());
          const Eigen::Vector3d target_rate = inboard.orientation * (frame.inboard_rest.conjugate() * drive->target_angular_velocity);
          for (int r = 0; r < controlled.count; ++r) {
            const Eigen::Vector3d& e = frame_vectors[rows[r].direction];
            rows[r].drive_error = error_vector.dot(e), rows[r].target_rate = target_rate.dot(e);
          }
        }
        break;
      }
      case JointType::fixed:
      case JointType::serial: break;
    }
  }
}

}  // namespace limber
