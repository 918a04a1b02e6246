#include "limber/kernel/featherstone/dynamics.hpp"

#include "limber/kernel/featherstone/joint_space_factor.hpp"

#include "limber/kernel/numerics/small_cholesky.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <Eigen/Geometry>

namespace limber {
namespace {

// v_J = S q̇ for body i's slice of v (`joint_velocities` points at it).
inline SpatialVector joint_velocity(const ArticulatedBody& body, const double* joint_velocities) {
  SpatialVector out = SpatialVector::Zero();
  switch (body.joint) {
    case ArticulatedJoint::revolute: out.head<3>() = body.joint_axis * joint_velocities[0]; break;
    case ArticulatedJoint::prismatic: out.tail<3>() = body.joint_axis * joint_velocities[0]; break;
    case ArticulatedJoint::spherical: out.head<3>() = Eigen::Vector3d::Map(joint_velocities); break;
    case ArticulatedJoint::floating: out = SpatialVector::Map(joint_velocities); break;
    case ArticulatedJoint::fixed: break;
  }
  return out;
}

// Sᵀ f into `out` (k values).
inline void project_force(const ArticulatedBody& body, const SpatialVector& f, double* out) {
  switch (body.joint) {
    case ArticulatedJoint::revolute: out[0] = body.joint_axis.dot(f.head<3>()); break;
    case ArticulatedJoint::prismatic: out[0] = body.joint_axis.dot(f.tail<3>()); break;
    case ArticulatedJoint::spherical: Eigen::Vector3d::Map(out) = f.head<3>(); break;
    case ArticulatedJoint::floating: SpatialVector::Map(out) = f; break;
    case ArticulatedJoint::fixed: break;
  }
}

void require_size(Eigen::Index actual, int expected, const char* what) {
  if (actual != expected) {
    throw std::invalid_argument(std::string(what) + ": expected size " + std::to_string(expected) + ", got " +
                                std::to_string(actual));
  }
}

// First pass of ABA and RNEA: ⁱX_λ (unless `q` is null: the workspace holds them), v_i = ⁱX_λ v_λ +
// v_J and c_i = v_i × v_J (Tables 5.1, 7.1), for the bodies of `range`.
void propagate_velocities(const ArticulatedTree& tree, const double* q, const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& w,
                          BodyRange range) {
  for (int i = range.first; i < range.last; ++i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    if (q) w.parent_to_body[index] = joint_transform(body, q + tree.position_offset(i)) * body.tree_transform;
    const SpatialVector joint_motion = joint_velocity(body, v.data() + tree.velocity_offset(i));
    if (body.parent >= 0) {
      w.velocity[index] = w.parent_to_body[index].apply_motion(w.velocity[static_cast<std::size_t>(body.parent)]) + joint_motion;
    } else {
      w.velocity[index] = joint_motion;
    }
    w.bias_acceleration[index] = cross_motion(w.velocity[index], joint_motion);
  }
}

SpatialVector base_acceleration(const Eigen::Vector3d& gravity) {
  SpatialVector a0;
  a0 << 0, 0, 0, -gravity;
  return a0;
}

}  // namespace

void DynamicsWorkspace::resize(const ArticulatedTree& tree) {
  const auto n = static_cast<std::size_t>(tree.body_count());
  parent_to_body.assign(n, PluckerTransform{});
  world_to_body.assign(n, PluckerTransform{});
  velocity.assign(n, SpatialVector::Zero());
  bias_acceleration.assign(n, SpatialVector::Zero());
  acceleration.assign(n, SpatialVector::Zero());
  bias_force.assign(n, SpatialVector::Zero());
  articulated_inertia.assign(n, SpatialMatrix::Zero());
  composite_inertia.assign(n, SpatialInertia{});
  projected_inertia.setZero(6, tree.velocity_count());
  joint_inertia_inverse.setZero(6, tree.velocity_count());
  joint_bias.setZero(tree.velocity_count());
}

bool DynamicsWorkspace::fits(const ArticulatedTree& tree) const {
  return velocity.size() == static_cast<std::size_t>(tree.body_count()) && joint_bias.size() == tree.velocity_count();
}

PluckerTransform joint_transform(const ArticulatedBody& body, const double* joint_positions) {
  PluckerTransform x;
  switch (body.joint) {
    case ArticulatedJoint::revolute: {
      // E = R(a, θ)ᵀ = 1 − sin θ [a]× + (1 − cos θ) [a]×²  (Rodrigues; Featherstone's rotx/y/z).
      const double angle = joint_positions[0];
      const Eigen::Matrix3d ax = skew(body.joint_axis);
      x.rotation = Eigen::Matrix3d::Identity() - std::sin(angle) * ax + (1 - std::cos(angle)) * (ax * ax);
      break;
    }
    case ArticulatedJoint::prismatic: x.translation = body.joint_axis * joint_positions[0]; break;
    case ArticulatedJoint::spherical: {
      const Eigen::Quaterniond orientation(joint_positions[0], joint_positions[1], joint_positions[2], joint_positions[3]);
      x.rotation = orientation.normalized().toRotationMatrix().transpose();
      break;
    }
    case ArticulatedJoint::floating: {
      const Eigen::Quaterniond orientation(joint_positions[3], joint_positions[4], joint_positions[5], joint_positions[6]);
      x.rotation = orientation.normalized().toRotationMatrix().transpose();
      x.translation = Eigen::Vector3d::Map(joint_positions);
      break;
    }
    case ArticulatedJoint::fixed: break;
  }
  return x;
}

namespace {
// ⁱX_0 = ⁱX_λ ^λX_0 from parent_to_body, outward, for the bodies of `range`.
void compose_world_transforms(const ArticulatedTree& tree, DynamicsWorkspace& w, BodyRange range) {
  for (int i = range.first; i < range.last; ++i) {
    const auto index = static_cast<std::size_t>(i);
    const int parent = tree.body(i).parent;
    w.world_to_body[index] = parent >= 0 ? w.parent_to_body[index] * w.world_to_body[static_cast<std::size_t>(parent)] : w.parent_to_body[index];
  }
}
}  // namespace

void body_poses(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace) {
  if (!workspace.fits(tree)) workspace.resize(tree);
  body_poses(tree, q, workspace, tree.all_bodies());
}

void body_poses(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace, BodyRange range) {
  require_size(q.size(), tree.position_count(), "body_poses: q");
  if (!workspace.fits(tree)) throw std::invalid_argument("body_poses: the workspace is not sized for this tree");
  for (int i = range.first; i < range.last; ++i) {
    workspace.parent_to_body[static_cast<std::size_t>(i)] =
        joint_transform(tree.body(i), q.data() + tree.position_offset(i)) * tree.body(i).tree_transform;
  }
  compose_world_transforms(tree, workspace, range);
}

void forward_kinematics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace) {
  require_size(q.size(), tree.position_count(), "forward_kinematics: q");
  require_size(v.size(), tree.velocity_count(), "forward_kinematics: v");
  if (!workspace.fits(tree)) workspace.resize(tree);
  forward_kinematics(tree, q, v, workspace, tree.all_bodies());
}

void forward_kinematics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace, BodyRange range) {
  require_size(q.size(), tree.position_count(), "forward_kinematics: q");
  require_size(v.size(), tree.velocity_count(), "forward_kinematics: v");
  if (!workspace.fits(tree)) throw std::invalid_argument("forward_kinematics: the workspace is not sized for this tree");
  propagate_velocities(tree, q.data(), v, workspace, range);
  compose_world_transforms(tree, workspace, range);
}

void body_velocities(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace) {
  body_velocities(tree, v, workspace, tree.all_bodies());
}

void body_velocities(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace, BodyRange range) {
  require_size(v.size(), tree.velocity_count(), "body_velocities: v");
  if (!workspace.fits(tree)) throw std::invalid_argument("body_velocities: the workspace holds no poses of this tree");
  propagate_velocities(tree, nullptr, v, workspace, range);
}

namespace {

// Table 7.1, with `armature` (nv, or nullptr: none) added to each D_i's diagonal; the poses ⁱX_λ,
// body velocities v_i and bias accelerations c_i from q (nq) and v into the workspace, or, q null,
// those `motion` holds (forward_kinematics of the current q and v); for the bodies of `range`
// (joint_accelerations sized nv, written on their coordinates).
void articulated_body_algorithm(const ArticulatedTree& tree, const double* q, const DynamicsWorkspace* motion,
                                const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                                const double* armature, const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace,
                                Eigen::VectorXd& joint_accelerations, BodyRange range) {
  if (!motion) require_size(v.size(), tree.velocity_count(), "forward_dynamics: v");
  require_size(joint_forces.size(), tree.velocity_count(), "forward_dynamics: joint forces");
  if (!workspace.fits(tree)) workspace.resize(tree);
  if (joint_accelerations.size() != tree.velocity_count()) joint_accelerations.resize(tree.velocity_count());
  DynamicsWorkspace& w = workspace;

  // Pass 1 (outward): velocities, bias accelerations; I^A_i = I_i, p^A_i = v_i ×* I_i v_i.
  if (!motion) propagate_velocities(tree, q, v, w, range);
  const DynamicsWorkspace& known = motion ? *motion : w;
  for (int i = range.first; i < range.last; ++i) {
    const auto index = static_cast<std::size_t>(i);
    const SpatialInertia& inertia = tree.body(i).inertia;
    w.articulated_inertia[index] = inertia.matrix();
    w.bias_force[index] = cross_force(known.velocity[index], inertia * known.velocity[index]);
  }

  // Pass 2 (inward): U_i = I^A_i S_i, D_i = S_iᵀ U_i, u_i = τ_i − S_iᵀ p^A_i; the body's
  // articulated inertia I^a = I^A − U D⁻¹ Uᵀ and bias force p^a = p^A + I^a c + U D⁻¹ u, as
  // seen through its joint, are added to the parent's.
  for (int i = range.last - 1; i >= range.first; --i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    const SpatialMatrix& ia = w.articulated_inertia[index];
    const SpatialVector& pa = w.bias_force[index];
    SpatialMatrix ia_through_joint;
    SpatialVector pa_through_joint;
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k == 0) {
        ia_through_joint = ia;
        pa_through_joint = pa + ia * known.bias_acceleration[index];
      } else {
        const Eigen::Matrix<double, 6, k> s = motion_subspace<k>(body);
        const Eigen::Matrix<double, 6, k> u_matrix = ia * s;
        Eigen::Matrix<double, k, k> d = s.transpose() * u_matrix;
        if constexpr (k == 1) d(0, 0) += body.armature;
        if (armature) d.diagonal() += Eigen::Matrix<double, k, 1>::Map(armature + offset);
        // D is symmetric positive definite: cofactors up to 3×3, a written-out Cholesky beyond,
        // the floating base's 6×6 (Eigen's LLT solves a matrix by its blocked path, which was a
        // fifth of a spherical chain's ABA in perf).
        const Eigen::Matrix<double, k, k> d_inverse = positive_definite_inverse<k, double>(d);
        const Eigen::Matrix<double, k, 1> u = joint_forces.template segment<k>(offset) - s.transpose() * pa;
        w.projected_inertia.template middleCols<k>(offset) = u_matrix;
        w.joint_inertia_inverse.template block<k, k>(0, offset) = d_inverse;
        w.joint_bias.template segment<k>(offset) = u;
        if (body.parent < 0) return;
        const Eigen::Matrix<double, 6, k> u_d_inverse = u_matrix * d_inverse;
        ia_through_joint.noalias() = ia - u_d_inverse * u_matrix.transpose();
        pa_through_joint.noalias() = pa + ia_through_joint * known.bias_acceleration[index] + u_d_inverse * u;
      }
    });
    if (body.parent < 0) continue;
    const auto parent = static_cast<std::size_t>(body.parent);
    w.articulated_inertia[parent] += known.parent_to_body[index].transpose_apply_inertia(ia_through_joint);
    w.bias_force[parent] += known.parent_to_body[index].transpose_apply_force(pa_through_joint);
  }

  // Pass 3 (outward): a' = ⁱX_λ a_λ + c_i, v̇_i = D_i⁻¹ (u_i − U_iᵀ a'), a_i = a' + S_i v̇_i.
  const SpatialVector a0 = base_acceleration(gravity);
  for (int i = range.first; i < range.last; ++i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    const SpatialVector& parent_acceleration = body.parent >= 0 ? w.acceleration[static_cast<std::size_t>(body.parent)] : a0;
    const SpatialVector a = known.parent_to_body[index].apply_motion(parent_acceleration) + known.bias_acceleration[index];
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k == 0) {
        w.acceleration[index] = a;
      } else {
        const Eigen::Matrix<double, k, 1> joint_acceleration =
            w.joint_inertia_inverse.template block<k, k>(0, offset) *
            (w.joint_bias.template segment<k>(offset) - w.projected_inertia.template middleCols<k>(offset).transpose() * a);
        joint_accelerations.template segment<k>(offset) = joint_acceleration;
        w.acceleration[index] = a + motion_subspace<k>(body) * joint_acceleration;
      }
    });
  }
}

}  // namespace

void forward_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace, Eigen::VectorXd& joint_accelerations) {
  forward_dynamics(tree, q, v, joint_forces, gravity, workspace, joint_accelerations, tree.all_bodies());
}

void forward_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace, Eigen::VectorXd& joint_accelerations, BodyRange range) {
  require_size(q.size(), tree.position_count(), "forward_dynamics: q");
  articulated_body_algorithm(tree, q.data(), nullptr, v, joint_forces, nullptr, gravity, workspace, joint_accelerations, range);
}

void forward_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const Eigen::Ref<const Eigen::VectorXd>& armature, const Eigen::Vector3d& gravity,
                      DynamicsWorkspace& workspace, Eigen::VectorXd& joint_accelerations) {
  require_size(q.size(), tree.position_count(), "forward_dynamics: q");
  require_size(armature.size(), tree.velocity_count(), "forward_dynamics: armature");
  articulated_body_algorithm(tree, q.data(), nullptr, v, joint_forces, armature.data(), gravity, workspace, joint_accelerations,
                             tree.all_bodies());
}

void forward_dynamics(const ArticulatedTree& tree, const DynamicsWorkspace& kinematics, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const double* armature, const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace,
                      Eigen::VectorXd& joint_accelerations) {
  forward_dynamics(tree, kinematics, joint_forces, armature, gravity, workspace, joint_accelerations, tree.all_bodies());
}

void forward_dynamics(const ArticulatedTree& tree, const DynamicsWorkspace& kinematics, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const double* armature, const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace,
                      Eigen::VectorXd& joint_accelerations, BodyRange range) {
  if (!kinematics.fits(tree)) throw std::invalid_argument("forward_dynamics: the kinematics are not of this tree");
  articulated_body_algorithm(tree, nullptr, &kinematics, Eigen::VectorXd(), joint_forces, armature, gravity, workspace, joint_accelerations,
                             range);
}

namespace {

// Table 5.1 for the bodies of `range`: the joint forces τ on their coordinates (joint_forces sized
// nv) that give accelerations v̇ (nv, or null: v̇ = 0, the bias forces C). The poses ⁱX_λ, body
// velocities v_i and bias accelerations c_i from q and v into w; or, `motion` not null, those it
// holds (forward_kinematics of the current q and v).
void recursive_newton_euler(const ArticulatedTree& tree, const double* q, const DynamicsWorkspace* motion,
                            const Eigen::Ref<const Eigen::VectorXd>& v, const double* joint_accelerations, const Eigen::Vector3d& gravity,
                            DynamicsWorkspace& w, Eigen::VectorXd& joint_forces, BodyRange range) {
  if (!motion) propagate_velocities(tree, q, v, w, range);
  const DynamicsWorkspace& known = motion ? *motion : w;
  // Outward: a_i = ⁱX_λ a_λ + S_i v̇_i + c_i; f_i = I_i a_i + v_i ×* I_i v_i (the net force the
  // body needs, by the Newton–Euler equation).
  const SpatialVector a0 = base_acceleration(gravity);
  for (int i = range.first; i < range.last; ++i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const SpatialVector& parent_acceleration = body.parent >= 0 ? w.acceleration[static_cast<std::size_t>(body.parent)] : a0;
    w.acceleration[index] = known.parent_to_body[index].apply_motion(parent_acceleration);
    if (joint_accelerations) w.acceleration[index] += joint_velocity(body, joint_accelerations + tree.velocity_offset(i));
    w.acceleration[index] += known.bias_acceleration[index];
    const SpatialVector& velocity = known.velocity[index];
    w.bias_force[index] = body.inertia * w.acceleration[index] + cross_force(velocity, body.inertia * velocity);
  }
  // Inward: τ_i = S_iᵀ f_i (plus the armature's a·v̇_i); the joint transmits f_i to the parent,
  // f_λ += λX_i* f_i.
  for (int i = range.last - 1; i >= range.first; --i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    project_force(body, w.bias_force[index], joint_forces.data() + offset);
    if (joint_accelerations && body.armature > 0) joint_forces[offset] += body.armature * joint_accelerations[offset];
    if (body.parent >= 0) {
      w.bias_force[static_cast<std::size_t>(body.parent)] += known.parent_to_body[index].transpose_apply_force(w.bias_force[index]);
    }
  }
}

}  // namespace

void inverse_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_accelerations,
                      const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace, Eigen::VectorXd& joint_forces) {
  require_size(q.size(), tree.position_count(), "inverse_dynamics: q");
  require_size(v.size(), tree.velocity_count(), "inverse_dynamics: v");
  require_size(joint_accelerations.size(), tree.velocity_count(), "inverse_dynamics: joint accelerations");
  if (!workspace.fits(tree)) workspace.resize(tree);
  joint_forces.resize(tree.velocity_count());
  recursive_newton_euler(tree, q.data(), nullptr, v, joint_accelerations.data(), gravity, workspace, joint_forces, tree.all_bodies());
}

void bias_forces(const ArticulatedTree& tree, const DynamicsWorkspace& kinematics, const Eigen::Vector3d& gravity,
                 DynamicsWorkspace& workspace, Eigen::VectorXd& forces, BodyRange range) {
  require_size(forces.size(), tree.velocity_count(), "bias_forces: the forces");
  if (!kinematics.fits(tree)) throw std::invalid_argument("bias_forces: the kinematics are not of this tree");
  if (!workspace.fits(tree)) throw std::invalid_argument("bias_forces: the workspace is not sized for this tree");
  recursive_newton_euler(tree, nullptr, &kinematics, Eigen::VectorXd(), nullptr, gravity, workspace, forces, range);
}

namespace {

// The composite-rigid-body algorithm (Table 6.2): calls store(row, column, H_row,column) once for
// each entry with `row` an earlier coordinate of the column's own joint or of an ancestor's, or
// the column itself (the upper triangle of H by block, as ancestors come first; the armature on
// the diagonal included). Every other entry of H is zero. A column's entries come together: the
// diagonal first, then its rows nearest first, up the path to the root (the factor's order,
// JointSpaceFactor::inertia_path).
// The poses are `parent_to_body` (ⁱX_λ per body); the bodies those of `range`.
template <typename Store>
void composite_inertia(const ArticulatedTree& tree, const std::vector<PluckerTransform>& parent_to_body, DynamicsWorkspace& w,
                       BodyRange range, Store&& store) {
  // Composite inertias, inward: I^c_λ += λX_i* I^c_i ⁱX_λ, each a rigid body's (m, h, Ī).
  for (int i = range.first; i < range.last; ++i) w.composite_inertia[static_cast<std::size_t>(i)] = tree.body(i).inertia;
  for (int i = range.last - 1; i >= range.first; --i) {
    const int parent = tree.body(i).parent;
    if (parent < 0) continue;
    const auto index = static_cast<std::size_t>(i);
    w.composite_inertia[static_cast<std::size_t>(parent)] += w.composite_inertia[index].transformed_by(parent_to_body[index]);
  }
  // For each joint's column of unit motions: F = I^c_i S_i, H_ii = S_iᵀ F; then F is carried
  // inward to each ancestor j, H_ji = S_jᵀ F (= H_ijᵀ).
  double projected[6];
  for (int i = range.last - 1; i >= range.first; --i) {
    const ArticulatedBody& body = tree.body(i);
    const int k = joint_velocity_count(body.joint);
    const int column = tree.velocity_offset(i);
    for (int c = 0; c < k; ++c) {
      double unit[6] = {0, 0, 0, 0, 0, 0};
      unit[c] = 1;
      SpatialVector f = w.composite_inertia[static_cast<std::size_t>(i)] * joint_velocity(body, unit);
      project_force(body, f, projected);
      store(column + c, column + c, projected[c] + body.armature);
      for (int r = c - 1; r >= 0; --r) store(column + r, column + c, projected[r]);
      for (int j = i; tree.body(j).parent >= 0;) {
        f = parent_to_body[static_cast<std::size_t>(j)].transpose_apply_force(f);
        j = tree.body(j).parent;
        project_force(tree.body(j), f, projected);
        for (int r = joint_velocity_count(tree.body(j).joint) - 1; r >= 0; --r) store(tree.velocity_offset(j) + r, column + c, projected[r]);
      }
    }
  }
}

// composite_inertia's store into a factor's slots: a column's diagonal, then its path in order.
struct PathStore {
  JointSpaceFactor& factor;
  double* next = nullptr;
  void operator()(int row, int column, double value) {
    if (row == column) {
      factor.set_inertia(column, column, value);
      next = factor.inertia_path(column);
    } else {
      *next++ = value;
    }
  }
};

}  // namespace

void mass_matrix(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace,
                 Eigen::MatrixXd& joint_space_inertia) {
  require_size(q.size(), tree.position_count(), "mass_matrix: q");
  if (!workspace.fits(tree)) workspace.resize(tree);
  const int nv = tree.velocity_count();
  joint_space_inertia.setZero(nv, nv);
  body_poses(tree, q, workspace);
  composite_inertia(tree, workspace.parent_to_body, workspace, tree.all_bodies(), [&](int row, int column, double value) {
    joint_space_inertia(row, column) = value;
    joint_space_inertia(column, row) = value;
  });
}

void mass_matrix(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace,
                 JointSpaceFactor& factor) {
  require_size(q.size(), tree.position_count(), "mass_matrix: q");
  require_size(factor.size(), tree.velocity_count(), "mass_matrix: the factor's coordinates");
  body_poses(tree, q, workspace);
  composite_inertia(tree, workspace.parent_to_body, workspace, tree.all_bodies(), PathStore{factor});
}

void mass_matrix(const ArticulatedTree& tree, const DynamicsWorkspace& poses, DynamicsWorkspace& workspace, JointSpaceFactor& factor) {
  if (!workspace.fits(tree)) workspace.resize(tree);
  mass_matrix(tree, poses, workspace, factor, tree.all_bodies());
}

void mass_matrix(const ArticulatedTree& tree, const DynamicsWorkspace& poses, DynamicsWorkspace& workspace, JointSpaceFactor& factor,
                 BodyRange range) {
  require_size(factor.size(), tree.velocity_count(), "mass_matrix: the factor's coordinates");
  if (!poses.fits(tree)) throw std::invalid_argument("mass_matrix: the poses are not of this tree");
  if (!workspace.fits(tree)) throw std::invalid_argument("mass_matrix: the workspace is not sized for this tree");
  composite_inertia(tree, poses.parent_to_body, workspace, range, PathStore{factor});
}

}  // namespace limber
