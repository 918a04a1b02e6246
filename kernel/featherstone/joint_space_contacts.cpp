#include "limber/kernel/featherstone/joint_space_contacts.hpp"

#include <algorithm>
#include <functional>
#include <cmath>
#include <limits>

#include "limber/kernel/featherstone/joint_space_limits.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"

namespace limber {
namespace {

using namespace joint_space;

// --- Contacts ------------------------------------------------------------------------------------

// Contact c's rows J_c (joint_space_contacts.hpp, "Responses"): for each of its tree bodies, the
// generalized impulses of unit world impulses along x, y, z at its point — the spatial impulses
// carried from the body to the root, τ_k = S_kᵀ f on every joint k on the way (Table 5.1's inward
// pass) — b's negated.
void contact_rows(FeatherstoneState& state, const RigidContact& contact) {
  JointSpaceContactScratch& s = state.contact;
  const ArticulatedTree& tree = state.tree;
  for (const std::int32_t scene_body : {contact.a, contact.b}) {
    if (scene_body < 0) continue;  // a plane
    const double sign = scene_body == contact.a ? 1.0 : -1.0;
    int i = state.tree_body[scene_body];
    const PluckerTransform& world_to_body = state.kinematics.world_to_body[static_cast<std::size_t>(i)];
    SpatialVector f[3];
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d impulse = sign * Eigen::Vector3d::Unit(axis);
      f[axis] << world_to_body.rotation * (contact.point - world_to_body.translation).cross(impulse), world_to_body.rotation * impulse;
    }
    for (;;) {
      const ArticulatedBody& body = tree.body(i);
      with_degrees_of_freedom(body.joint, [&](auto dofs) {
        constexpr int k = decltype(dofs)::value;
        if constexpr (k > 0) {
          Eigen::Matrix<double, k, 1> on_joint[3];
          for (int axis = 0; axis < 3; ++axis) on_joint[axis] = project_on_joint<k>(body, f[axis]);
          for (int r = 0; r < k; ++r) {
            s.row_coordinate.push_back(tree.velocity_offset(i) + r);
            s.row_value.emplace_back(on_joint[0][r], on_joint[1][r], on_joint[2][r]);
          }
        }
      });
      if (body.parent < 0) break;
      for (SpatialVector& force : f) force = state.kinematics.parent_to_body[static_cast<std::size_t>(i)].transpose_apply_force(force);
      i = body.parent;
    }
  }
  s.row_begin.push_back(static_cast<int>(s.row_coordinate.size()));
}

// The entries of limit row `row`'s block: direction on its joint's velocities, zeros on the
// rest of its path to the root (joint_space_contacts.hpp, "Constraint space").
void limit_row_entries(FeatherstoneState& state, const JointLimitRow& row) {
  JointSpaceContactScratch& s = state.contact;
  for (int i = row.body; i >= 0; i = state.tree.body(i).parent) {
    const int offset = state.tree.velocity_offset(i), dofs = joint_velocity_count(state.tree.body(i).joint);
    for (int k = offset; k < offset + dofs; ++k) {
      const int m = k - row.offset;
      s.row_coordinate.push_back(k);
      s.row_value.emplace_back(m >= 0 && m < row.dofs ? row.direction[m] : 0.0, 0.0, 0.0);
    }
  }
  s.row_begin.push_back(static_cast<int>(s.row_coordinate.size()));
}

// J_g x: block g's rows' motion (m/s for velocities x = v, m for a push-out's displacement).
Eigen::Vector3d block_motion(const JointSpaceContactScratch& s, std::size_t g, const Eigen::VectorXd& x) {
  Eigen::Vector3d motion = Eigen::Vector3d::Zero();
  for (int e = s.row_begin[g]; e < s.row_begin[g + 1]; ++e) motion += s.row_value[static_cast<std::size_t>(e)] * x[s.row_coordinate[static_cast<std::size_t>(e)]];
  return motion;
}

// Block g's half rows Y_g = L⁻ᵀ J_gᵀ (on its path). Needs its rows and the factor.
void half_rows(JointSpaceContactScratch& s, std::size_t g) {
  s.path.clear();
  for (int e = s.row_begin[g]; e < s.row_begin[g + 1]; ++e) {
    const int k = s.row_coordinate[static_cast<std::size_t>(e)];
    s.scatter.row(k) += s.row_value[static_cast<std::size_t>(e)].transpose();
    s.path.push_back(k);
  }
  std::sort(s.path.begin(), s.path.end(), std::greater<>());
  s.path.erase(std::unique(s.path.begin(), s.path.end()), s.path.end());
  s.factor.solve_transposed_lower(s.scatter, s.path);
  for (const int k : s.path) {
    s.half_coordinate.push_back(k);
    s.half_value.push_back(s.scatter.row(k).transpose());
    s.scatter.row(k).setZero();
  }
  s.half_begin.push_back(static_cast<int>(s.half_coordinate.size()));
}

// A_hg = Y_hᵀ D⁻¹ Y_g (3 × 3) of blocks h and g, with D⁻¹ Y_g in s.scatter on g's path; a limit
// row's block (`h_row`, `g_row`: one row) has only its first row or column.
Eigen::Matrix3d delassus_block(const JointSpaceContactScratch& s, std::size_t h, bool h_row, bool g_row) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  for (int e = s.half_begin[h]; e < s.half_begin[h + 1]; ++e) {
    const Eigen::Vector3d& y = s.half_value[static_cast<std::size_t>(e)];
    const auto z = s.scatter.row(s.half_coordinate[static_cast<std::size_t>(e)]);
    if (h_row && g_row) {
      a(0, 0) += y[0] * z[0];
    } else if (h_row) {
      a.row(0) += y[0] * z;
    } else if (g_row) {
      a.col(0) += z[0] * y;
    } else {
      a.noalias() += y * z;
    }
  }
  return a;
}

// The blocks by island (a block on two islands in both), and each one's place in its first
// island's list.
void group_blocks_by_island(FeatherstoneState& state) {
  JointSpaceContactScratch& s = state.contact;
  const std::size_t blocks = s.first_island.size();
  s.island_block_begin.assign(state.islands.size() + 1, 0);
  for (std::size_t g = 0; g < blocks; ++g) {
    ++s.island_block_begin[static_cast<std::size_t>(s.first_island[g]) + 1];
    if (s.second_island[g] >= 0) ++s.island_block_begin[static_cast<std::size_t>(s.second_island[g]) + 1];
  }
  for (std::size_t k = 0; k < state.islands.size(); ++k) s.island_block_begin[k + 1] += s.island_block_begin[k];
  s.island_block.resize(static_cast<std::size_t>(s.island_block_begin.back()));
  for (std::size_t g = 0; g < blocks; ++g) {  // each island's begin runs to its end...
    for (const std::int32_t island : {s.first_island[g], s.second_island[g]}) {
      if (island >= 0) s.island_block[static_cast<std::size_t>(s.island_block_begin[static_cast<std::size_t>(island)]++)] = static_cast<int>(g);
    }
  }
  for (std::size_t k = state.islands.size(); k > 0; --k) s.island_block_begin[k] = s.island_block_begin[k - 1];  // ...and is put back
  s.island_block_begin[0] = 0;
  s.island_slot.resize(blocks);
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    for (int slot = s.island_block_begin[k]; slot < s.island_block_begin[k + 1]; ++slot) {
      const auto g = static_cast<std::size_t>(s.island_block[static_cast<std::size_t>(slot)]);
      if (static_cast<std::size_t>(s.first_island[g]) == k) s.island_slot[g] = slot - s.island_block_begin[k];
    }
  }
}

// The Delassus matrix's block columns (joint_space_contacts.hpp, "Constraint space"): for each
// block g, A_hg for every block h on one of g's islands — through D⁻¹ Y_g scattered on g's path,
// or, for two blocks of one island alone, as A_ghᵀ from h's column when h came first. Needs the
// blocks' half rows and islands.
void form_delassus(FeatherstoneState& state) {
  JointSpaceContactScratch& s = state.contact;
  group_blocks_by_island(state);
  const std::size_t blocks = s.first_island.size();
  const std::size_t contacts = state.contacts.size();
  s.contact_matrix.resize(contacts);
  s.column_begin.assign(1, 0);
  s.column_block.clear(), s.column_value.clear();
  for (std::size_t g = 0; g < blocks; ++g) {
    const bool g_row = g >= contacts, g_alone = s.second_island[g] < 0;
    for (int e = s.half_begin[g]; e < s.half_begin[g + 1]; ++e) {
      const int k = s.half_coordinate[static_cast<std::size_t>(e)];
      s.scatter.row(k) = s.half_value[static_cast<std::size_t>(e)].transpose() / s.factor.pivot(k);
    }
    for (const std::int32_t island : {s.first_island[g], s.second_island[g]}) {
      if (island < 0) continue;
      const auto k = static_cast<std::size_t>(island);
      for (int slot = s.island_block_begin[k]; slot < s.island_block_begin[k + 1]; ++slot) {
        const auto h = static_cast<std::size_t>(s.island_block[static_cast<std::size_t>(slot)]);
        // A block on both of g's islands is met twice: take it on the first.
        if (island == s.second_island[g] && (s.first_island[h] == s.first_island[g] || s.second_island[h] == s.first_island[g])) continue;
        // h's column lists its one island's blocks in order: A_gh sits at g's place there.
        const Eigen::Matrix3d a = h < g && g_alone && s.second_island[h] < 0
                                      ? Eigen::Matrix3d(s.column_value[static_cast<std::size_t>(s.column_begin[h] + s.island_slot[g])].transpose())
                                      : delassus_block(s, h, h >= contacts, g_row);
        s.column_block.push_back(static_cast<int>(h));
        s.column_value.push_back(a);
        if (h != g) continue;  // the diagonal: a contact's K, a limit row's inverse mass
        if (g < contacts) {
          s.contact_matrix[g] = a;
        } else {
          state.controls.rows[g - contacts].inverse_mass = a(0, 0);
        }
      }
    }
    s.column_begin.push_back(static_cast<int>(s.column_block.size()));
    for (int e = s.half_begin[g]; e < s.half_begin[g + 1]; ++e) s.scatter.row(s.half_coordinate[static_cast<std::size_t>(e)]).setZero();
  }
}

// The blocks' motions J_g x and impulses 0, for passes on x.
void start_passes(JointSpaceContactScratch& s, const Eigen::VectorXd& x) {
  const std::size_t blocks = s.first_island.size();
  s.motion.resize(blocks), s.impulse.resize(blocks);
  for (std::size_t g = 0; g < blocks; ++g) s.motion[g] = block_motion(s, g, x), s.impulse[g].setZero();
}

// x += H⁻¹ Σ_g J_gᵀ λ_g = L⁻¹ D⁻¹ Σ_g Y_g λ_g: the passes' impulses joined to x (v, or the
// push-out's displacement), one forward pass.
void settle(JointSpaceContactScratch& s, Eigen::VectorXd& x) {
  for (std::size_t g = 0; g < s.impulse.size(); ++g) {
    if (s.impulse[g].isZero(0)) continue;
    for (int e = s.half_begin[g]; e < s.half_begin[g + 1]; ++e) {
      const int k = s.half_coordinate[static_cast<std::size_t>(e)];
      s.lagging[k] += s.half_value[static_cast<std::size_t>(e)].dot(s.impulse[g]) / s.factor.pivot(k);
    }
  }
  s.factor.solve_lower(s.lagging);
  x += s.lagging;
  s.lagging.setZero();
}

// Sequential impulses (joint_space_contacts.hpp, "Impulses") on the contacts' blocks, and the
// limit rows' blocks held per island, in constraint space; v takes them at the end.
void impulse_passes(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  start_passes(s, state.v);
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool applied = false;  // a pass that applies nothing leaves nothing for the next
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      const Eigen::Matrix3d& k = s.contact_matrix[c];
      const Eigen::Vector3d& normal = contact.normal;
      const Eigen::Vector3d relative = s.motion[c];
      const double normal_speed = relative.dot(normal);
      const double normal_inverse_mass = normal.dot(k * normal);
      if (normal_speed >= -kSlowestApproach || !(normal_inverse_mass > 0)) continue;
      const double normal_impulse = -(1 + contact.restitution) * normal_speed / normal_inverse_mass;
      Eigen::Vector3d impulse = normal_impulse * normal;
      const Eigen::Vector3d after = relative + k * impulse;
      const Eigen::Vector3d sliding = after - after.dot(normal) * normal;
      const double sliding_speed = sliding.norm();
      if (contact.friction > 0 && sliding_speed > 1e-12 * relative.norm()) {
        const Eigen::Vector3d tangent = sliding / sliding_speed;
        const double tangent_inverse_mass = tangent.dot(k * tangent);
        if (tangent_inverse_mass > 0) impulse -= std::min(sliding_speed / tangent_inverse_mass, contact.friction * normal_impulse) * tangent;
      }
      apply_block_impulse(s, static_cast<int>(c), impulse);
      applied = true;
    }
    // Limits: accumulated λ ≥ 0 with direction·v ≥ −max(C, 0)/Δt (restitution 0; a limit not yet
    // reached lets the joint arrive at it by the step's end), each island's rows together.
    if (!state.controls.rows.empty() && solve_limit_rows(state, dt, /*position=*/false)) applied = true;
    if (!applied) break;
  }
  settle(s, state.v);
}

// The position pass (joint_space_contacts.hpp, "Penetration").
void push_out(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.displacement.setZero();
  start_passes(s, s.displacement);
  bool moved = false;
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool pushed = false;
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      const double target = push_out_distance(contact, state.settings, dt);
      const double normal_inverse_mass = contact.normal.dot(s.contact_matrix[c] * contact.normal);
      if (!(target > 0) || !(normal_inverse_mass > 0)) continue;
      const double done = s.motion[c].dot(contact.normal);
      if (std::abs(target - done) <= kPushTolerance * target) continue;
      const double pushed_so_far = s.impulse[c].dot(contact.normal);  // the push-out's impulses are along the normal
      const double change = std::max(pushed_so_far + (target - done) / normal_inverse_mass, 0.0) - pushed_so_far;
      if (change == 0) continue;
      apply_block_impulse(s, static_cast<int>(c), change * contact.normal);
      moved = pushed = true;
    }
    if (!state.controls.rows.empty() && solve_limit_rows(state, dt, /*position=*/true)) moved = pushed = true;
    if (!pushed) break;
  }
  if (!moved) return;
  settle(s, s.displacement);
  // Every body's momentum in its own frame, I_i v_i, before the push-out (the impulses' v; the
  // poses are those detection saw).
  const ArticulatedTree& tree = state.tree;
  body_velocities(tree, state.v, state.kinematics);
  for (int i = 0; i < tree.body_count(); ++i) {
    const auto index = static_cast<std::size_t>(i);
    s.body_momentum[index] = tree.body(i).inertia * state.kinematics.velocity[index];
  }
  displace_positions(tree, state.q, s.displacement, state.q);
  body_poses(tree, state.q, state.kinematics);
  // The joint velocities that keep every body's motion in its own frame as closely as the joints
  // allow at the new pose, in the kinetic-energy metric: v = H⁻¹ Σ J_iᵀ I_i v_i, by the inward
  // pass and ABA with v = 0, g = 0. An H-orthogonal projection of motions whose energy is the old
  // one, so it never adds kinetic energy — where keeping v would: v holds relative velocities in
  // the child frames the push-out turned, and a limb spinning fast about its axis relative to its
  // parent would swing that spin onto its neighbours.
  joint_forces_of_body_forces(state, s.body_momentum, s.generalized_momentum);
  forward_dynamics(tree, state.kinematics, s.zero_velocities, s.generalized_momentum, nullptr, Eigen::Vector3d::Zero(), s.articulated, state.v);
}

// The island of scene body b (−1 for a plane).
std::int32_t island_of_scene_body(const FeatherstoneState& state, std::int32_t b) {
  return b < 0 ? -1 : static_cast<std::int32_t>(state.island_of_body[static_cast<std::size_t>(b)]);
}

// The step's blocks — the contacts, then the limit rows — their rows, half rows and Delassus
// matrix through the factor of H at the current q, approach speeds and e = 0 for resting
// contacts; false when there are none.
bool prepare_constraints(FeatherstoneState& state, double dt) {
  find_limit_rows(state, dt);
  if (state.contacts.empty() && state.controls.rows.empty()) return false;
  JointSpaceContactScratch& s = state.contact;
  mass_matrix(state.tree, state.kinematics, s.composite, s.inertia);  // at the poses detection saw
  s.factor = s.inertia;  // the same sizes: no allocation
  if (s.factor.factor() >= 0) {
    // H is positive definite at any finite pose; it is not only once the state has gone
    // non-finite. Say so through v, which the step's status checks, instead of answering the
    // contacts with a broken factor.
    state.v.setConstant(std::numeric_limits<double>::quiet_NaN());
    return false;
  }
  s.row_begin.assign(1, 0);
  s.row_coordinate.clear(), s.row_value.clear();
  s.half_begin.assign(1, 0);
  s.half_coordinate.clear(), s.half_value.clear();
  s.first_island.clear(), s.second_island.clear();
  for (std::size_t c = 0; c < state.contacts.size(); ++c) {
    RigidContact& contact = state.contacts[c];
    contact_rows(state, contact);
    half_rows(s, c);
    const std::int32_t a = island_of_scene_body(state, contact.a), b = island_of_scene_body(state, contact.b);
    s.first_island.push_back(a), s.second_island.push_back(b == a ? -1 : b);
    record_approach(contact, -block_motion(s, c, state.v).dot(contact.normal), state.settings, dt);
  }
  for (const JointLimitRow& row : state.controls.rows) {
    limit_row_entries(state, row);
    half_rows(s, s.first_island.size());
    s.first_island.push_back(row.island), s.second_island.push_back(-1);
  }
  form_delassus(state);
  return true;
}

// The passes leave state.kinematics' poses those of q (the push-out's body_poses when it moved
// q): the rigid bodies need only the new velocities.
void mirror_new_velocities(FeatherstoneState& state) {
  body_velocities(state.tree, state.v, state.kinematics);
  mirror_rigid_bodies(state);
}

}  // namespace

void apply_joint_space_impulses(FeatherstoneState& state, double dt) {
  if (!prepare_constraints(state, dt)) return;
  impulse_passes(state, dt);
  mirror_new_velocities(state);
}

void resolve_joint_space_contacts(FeatherstoneState& state, double dt) {
  if (!prepare_constraints(state, dt)) return;
  impulse_passes(state, dt);
  push_out(state, dt);
  mirror_new_velocities(state);
}

}  // namespace limber
