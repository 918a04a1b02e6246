#include "limber/kernel/featherstone/joint_space_contacts.hpp"

#include <algorithm>
#include <functional>
#include <cmath>
#include <limits>

#include "limber/kernel/featherstone/joint_space_limits.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/numerics/contact_projection.hpp"

namespace limber {
namespace {

using namespace joint_space;

// --- Contacts ------------------------------------------------------------------------------------

// Contact block g's rows J_c (joint_space_contacts.hpp, "Responses"), from row_begin[g]: for each
// of its tree bodies, the generalized impulses τ_k = S_kᵀ f of unit world impulses along x, y, z
// at its point, on every joint k on the way to the root — b's negated. Each row is taken in
// world coordinates, where a unit impulse e at p is the wrench (p × e, e) and a joint turning
// about the world axis u through o takes u·((p − o) × e) = e·(u × (p − o)): the geometric
// Jacobian's column, one cross product a coordinate instead of three wrenches carried joint by
// joint (Sᵀ of Table 5.1's inward pass).
void contact_rows(FeatherstoneState& state, std::size_t g, const RigidContact& contact) {
  JointSpaceContactScratch& s = state.contact;
  const ArticulatedTree& tree = state.tree;
  const Eigen::Matrix3d frame = contact_frame(contact.normal);
  auto entry = static_cast<std::size_t>(s.row_begin[g]);
  for (const std::int32_t scene_body : {contact.a, contact.b}) {
    if (scene_body < 0) continue;  // a plane
    const double sign = scene_body == contact.a ? 1.0 : -1.0;
    for (int i = state.tree_body[scene_body]; i >= 0; i = tree.body(i).parent) {
      const ArticulatedBody& body = tree.body(i);
      const PluckerTransform& world_to_body = state.kinematics.world_to_body[static_cast<std::size_t>(i)];
      const Eigen::Matrix3d& rotation = world_to_body.rotation;  // row m: the body's axis m in world coordinates
      const Eigen::Vector3d arm = contact.point - world_to_body.translation;
      int coordinate = tree.velocity_offset(i);
      const auto put = [&](const Eigen::Vector3d& value) {
        s.row_coordinate[entry] = coordinate++;
        s.row_value[entry] = sign * (frame * value);
        ++entry;
      };
      switch (body.joint) {
        case ArticulatedJoint::revolute: put((rotation.transpose() * body.joint_axis).cross(arm)); break;
        case ArticulatedJoint::prismatic: put(rotation.transpose() * body.joint_axis); break;
        case ArticulatedJoint::spherical:
          for (int m = 0; m < 3; ++m) put(rotation.row(m).transpose().cross(arm));
          break;
        case ArticulatedJoint::floating:
          for (int m = 0; m < 3; ++m) put(rotation.row(m).transpose().cross(arm));
          for (int m = 0; m < 3; ++m) put(rotation.row(m).transpose());
          break;
        case ArticulatedJoint::fixed: break;
      }
    }
  }
}

// Limit row block g's entries, from row_begin[g]: its direction on its joint's velocities, zeros
// on the rest of its path to the root (joint_space_contacts.hpp, "Constraint space").
void limit_row_entries(FeatherstoneState& state, std::size_t g, const JointLimitRow& row) {
  JointSpaceContactScratch& s = state.contact;
  auto entry = static_cast<std::size_t>(s.row_begin[g]);
  for (int i = row.body; i >= 0; i = state.tree.body(i).parent) {
    const int offset = state.tree.velocity_offset(i), dofs = joint_velocity_count(state.tree.body(i).joint);
    for (int k = offset; k < offset + dofs; ++k, ++entry) {
      const int m = k - row.offset;
      s.row_coordinate[entry] = k;
      s.row_value[entry] = Eigen::Vector3d(m >= 0 && m < row.dofs ? row.direction[m] : 0.0, 0.0, 0.0);
    }
  }
}

// J_g x: block g's rows' motion (m/s for velocities x = v, m for a push-out's displacement).
Eigen::Vector3d block_motion(const JointSpaceContactScratch& s, std::size_t g, const Eigen::VectorXd& x) {
  Eigen::Vector3d motion = Eigen::Vector3d::Zero();
  for (int e = s.row_begin[g]; e < s.row_begin[g + 1]; ++e) motion += s.row_value[static_cast<std::size_t>(e)] * x[s.row_coordinate[static_cast<std::size_t>(e)]];
  return motion;
}

// Block g's half rows Y_g = L⁻ᵀ J_gᵀ (on its path) and its diagonal block Y_gᵀ D⁻¹ Y_g. Needs
// its rows and the factor; `path` is scratch. A limit row (`one_column`) has its values in x
// alone: its solve takes that column.
Eigen::Matrix3d half_rows(JointSpaceContactScratch& s, std::size_t g, std::vector<int>& path, bool one_column) {
  path.clear();
  for (int e = s.row_begin[g]; e < s.row_begin[g + 1]; ++e) {
    const int k = s.row_coordinate[static_cast<std::size_t>(e)];
    s.scatter.row(k) += s.row_value[static_cast<std::size_t>(e)].transpose();
    path.push_back(k);
  }
  std::sort(path.begin(), path.end(), std::greater<>());
  path.erase(std::unique(path.begin(), path.end()), path.end());
  if (one_column) {
    s.factor.solve_transposed_lower_column(s.scatter.col(0), path);
  } else {
    s.factor.solve_transposed_lower(s.scatter, path);
  }
  Eigen::Matrix3d diagonal = Eigen::Matrix3d::Zero();
  auto entry = static_cast<std::size_t>(s.row_begin[g]);  // a block has no more half rows than rows
  for (const int k : path) {
    const Eigen::Vector3d y = s.scatter.row(k).transpose();
    s.scatter.row(k).setZero();
    s.half_coordinate[entry] = k;
    s.half_value[entry] = y;
    ++entry;
    diagonal.noalias() += (y * s.factor.inverse_pivot(k)) * y.transpose();
  }
  s.half_end[g] = static_cast<int>(entry);
  return diagonal;
}

// Calls visit(k, range) for each island k of `group` and its tree bodies.
template <typename Visit>
void for_each_island(const FeatherstoneState& state, const ConstraintGroup& group, Visit&& visit) {
  for (int n = group.first_island; n < group.last_island; ++n) {
    const auto k = static_cast<std::size_t>(state.contact.group_island[static_cast<std::size_t>(n)]);
    visit(k, island_bodies(state, k));
  }
}

// x += L⁻¹ y on the group's islands: the impulses so far joined to x (one forward pass); y = 0.
void settle(FeatherstoneState& state, const ConstraintGroup& group, Eigen::VectorXd& x) {
  JointSpaceContactScratch& s = state.contact;
  for_each_island(state, group, [&](std::size_t k, BodyRange) {
    const auto [first, last] = island_velocities(state, k);
    s.factor.solve_lower(s.lagging, first, last);
    x.segment(first, last - first) += s.lagging.segment(first, last - first);
    s.lagging.segment(first, last - first).setZero();
  });
}

// H + diag(armature) (armature: nv, or null) of island k at state.kinematics' poses into the
// factor, factored; s.factored[k] says whether it was positive definite.
void factor_island(FeatherstoneState& state, std::size_t k, BodyRange bodies, const double* armature) {
  JointSpaceContactScratch& s = state.contact;
  mass_matrix(state.tree, state.kinematics, s.composite, s.factor, bodies);
  const auto [first, last] = island_velocities(state, k);
  if (armature) {
    for (int i = first; i < last; ++i) {
      if (armature[i] != 0) s.factor.add_inertia(i, i, armature[i]);
    }
  }
  s.factored[k] = s.factor.factor(first, last) < 0;
}

// The group's impulses' change of kinetic energy, ½(v + Δv)ᵀH(v + Δv) − ½vᵀHv = λᵀJv + ½λᵀAλ
// (J, joules), from each block's motion before the impulses and with them; H is the factor's. An
// impulse past what stops its rows (a warm start the passes have not taken back, a bounce its
// neighbours' impulses reached before it) can make it positive: then every impulse is scaled by
// the largest α ≤ 1 with λᵀJv·α + ½λᵀAλ·α² ≤ 0, along the line to none — which stays in every
// cone. (MuJoCo likewise keeps a warm start only when its cost is below a cold start's.)
void keep_dissipative(FeatherstoneState& state, const ConstraintGroup& group) {
  JointSpaceContactScratch& s = state.contact;
  double work = 0, curvature = 0;  // λᵀJv, λᵀAλ
  for (int block = group.first_block; block < group.first_row_block; ++block) {
    const auto g = static_cast<std::size_t>(block);
    work += s.impulse[g].dot(s.free_motion[g]), curvature += s.impulse[g].dot(lagging_motion(s, g));
  }
  for (int block = group.first_row_block; block < group.last_block; ++block) {
    const auto g = static_cast<std::size_t>(block);
    const JointLimitRow& row = state.controls.rows[static_cast<std::size_t>(s.block_source[g])];
    work += row.impulse * joint_dot(row.direction, state.v, row.offset, row.dofs), curvature += row.impulse * lagging_motion(s, g)[0];
  }
  if (!(work + 0.5 * curvature > 0) || !(curvature > 0)) return;
  const double scale = std::clamp(-2 * work / curvature, 0.0, 1.0);
  for (int block = group.first_block; block < group.first_row_block; ++block) s.impulse[static_cast<std::size_t>(block)] *= scale;
  for (int block = group.first_row_block; block < group.last_block; ++block) state.controls.rows[static_cast<std::size_t>(s.block_source[static_cast<std::size_t>(block)])].impulse *= scale;
  for_each_island(state, group, [&](std::size_t k, BodyRange) {
    const auto [first, last] = island_velocities(state, k);
    s.lagging.segment(first, last - first) *= scale;
  });
}

// Projected Gauss–Seidel (joint_space_contacts.hpp, "Impulses") on the group's contacts and limit
// rows, from the contacts' warm start.
void impulse_passes(FeatherstoneState& state, const ConstraintGroup& group, double dt) {
  JointSpaceContactScratch& s = state.contact;
  const bool before_move = constraints_before_move(state);
  for (int block = group.first_block; block < group.last_block; ++block) {  // the warm start
    const auto g = static_cast<std::size_t>(block);
    const Eigen::Vector3d impulse =
        block < group.first_row_block ? s.impulse[g] : Eigen::Vector3d(state.controls.rows[static_cast<std::size_t>(s.block_source[g])].impulse, 0, 0);
    if (!impulse.isZero()) respond(s, g, impulse);
  }
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool applied = false;  // a pass that changes no speed by kSlowestApproach ends them
    for (int block = group.first_block; block < group.first_row_block; ++block) {
      const auto g = static_cast<std::size_t>(block);
      const RigidContact& contact = state.contacts[static_cast<std::size_t>(s.block_source[g])];
      const Eigen::Matrix3d& k = s.contact_matrix[g];
      const double target = contact_target_speed(contact, before_move, dt);
      const Eigen::Vector3d impulse =
          project_contact_impulse(k, s.free_motion[g] + lagging_motion(s, g), s.impulse[g], target, contact.friction);
      const Eigen::Vector3d change = impulse - s.impulse[g];
      if (!((k * change).lpNorm<Eigen::Infinity>() > kSlowestApproach)) continue;  // a change no speed would notice
      s.impulse[g] = impulse;
      respond(s, g, change);
      applied = true;
    }
    // Limits: accumulated λ ≥ 0 with direction·v ≥ −max(C, 0)/Δt (restitution 0; a limit not yet
    // reached lets the joint arrive at it by the step's end), each island's rows together.
    if (solve_limit_rows(state, group, dt, /*position=*/false, state.v)) applied = true;
    if (!applied) break;
  }
  keep_dissipative(state, group);
  settle(state, group, state.v);
}

// Island k (its tree bodies `bodies`) moved by the push-out's displacement, then the joint
// velocities that keep every body's motion in its own frame as closely as the joints allow at its
// new pose, in the kinetic-energy metric: the H-orthogonal projection
// v* = H⁻¹ (Σ J_iᵀ I_i v_i + A v) of the old motions v_i and armature momenta A v (H includes A),
// so it never adds kinetic energy. Keeping v would not do: v holds
// relative velocities in the child frames the push-out turned, and a limb spinning fast about its
// axis relative to its parent would swing that spin onto its neighbours.
// It is taken as a correction of v through H's factor at the new pose (the CRBA and LᵀDL of
// prepare_group, again): v* = v + H⁻¹ Σ J_iᵀ I_i (v_i − v_i(v)), v_i(v) the motions v gives at the
// new pose (A v cancels) — cheaper than the articulated-body pass with v = 0, g = 0 it replaces.
// The factor at the pose detection saw (tried) does not serve: light limbs beside a heavy trunk
// make H ill-conditioned enough that after a push-out of 5 mrad it missed the correction by three
// times its size (humanoid.json hit by the ball).
// Leaves the island's poses and body velocities in state.kinematics those of (q, v*) (v not finite
// when H was not positive definite: the step's status says so).
void displace_island(FeatherstoneState& state, std::size_t k, BodyRange bodies) {
  JointSpaceContactScratch& s = state.contact;
  const ArticulatedTree& tree = state.tree;
  const auto [first, last] = island_velocities(state, k);
  const auto on_island = [first = first, count = last - first](Eigen::VectorXd& x) { return x.segment(first, count); };
  // Every body's momentum in its own frame, I_i v_i, before the push-out (the impulses' v, at the
  // poses before it: detection's, or before the move those h·v moved to).
  body_velocities(tree, state.v, state.kinematics, bodies);
  for (int i = bodies.first; i < bodies.last; ++i) {
    const auto index = static_cast<std::size_t>(i);
    s.body_momentum[index] = tree.body(i).inertia * state.kinematics.velocity[index];
  }
  displace_positions(tree, state.q, s.displacement, state.q, bodies);
  body_poses(tree, state.q, state.kinematics, bodies);
  mass_matrix(tree, state.kinematics, s.composite, s.factor, bodies);
  if (!(s.factor.factor(first, last) < 0)) {
    on_island(state.v).setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  body_velocities(tree, state.v, state.kinematics, bodies);
  for (int i = bodies.first; i < bodies.last; ++i) {
    const auto index = static_cast<std::size_t>(i);
    s.body_momentum[index] -= tree.body(i).inertia * state.kinematics.velocity[index];
  }
  joint_forces_of_body_forces(state, s.body_momentum, s.generalized_momentum, bodies);
  s.factor.solve(s.generalized_momentum, first, last);
  on_island(state.v) += on_island(s.generalized_momentum);
  body_velocities(tree, state.v, state.kinematics, bodies);
  s.factored[k] = 0;  // the factor holds H at the new pose
}

// The position pass (joint_space_contacts.hpp, "Penetration") over the group.
// Returns whether it moved the group: then, after the move, state.kinematics holds its new poses
// and velocities; before the move (constraints_before_move) the displacement waits in
// s.displacement for advance_positions.
bool push_out(FeatherstoneState& state, const ConstraintGroup& group, double dt) {
  JointSpaceContactScratch& s = state.contact;
  const bool before_move = constraints_before_move(state);
  for_each_island(state, group, [&](std::size_t k, BodyRange) {
    const auto [first, last] = island_velocities(state, k);
    s.displacement.segment(first, last - first).setZero();
  });
  for (int g = group.first_block; g < group.first_row_block; ++g) s.push[static_cast<std::size_t>(g)] = 0;
  for (int g = group.first_row_block; g < group.last_block; ++g) state.controls.rows[static_cast<std::size_t>(s.block_source[static_cast<std::size_t>(g)])].push = 0;
  bool moved = false;
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool pushed = false;
    for (int block = group.first_block; block < group.first_row_block; ++block) {
      const auto g = static_cast<std::size_t>(block);
      const RigidContact& contact = state.contacts[static_cast<std::size_t>(s.block_source[g])];
      // Before the move the band keeps a resting contact, which the passes' tolerance lets sink by
      // ~10⁻⁷ m a step, from being pushed and re-projected every step.
      const double target = before_move ? push_out_before_move(contact, state.settings, dt) : push_out_distance(contact, state.settings, dt);
      const double normal_inverse_mass = s.contact_matrix[g](0, 0);
      if (!(target > 0) || !(normal_inverse_mass > 0)) continue;
      const double done = lagging_motion(s, g)[0];  // the displacement is all in y until settled
      if (std::abs(target - done) <= kPushTolerance * target) continue;
      const double push = std::max(s.push[g] + (target - done) / normal_inverse_mass, 0.0);
      const double change = push - s.push[g];
      if (change == 0) continue;
      s.push[g] = push;
      respond(s, g, Eigen::Vector3d(change, 0, 0));
      moved = pushed = true;
    }
    if (solve_limit_rows(state, group, dt, /*position=*/true, s.displacement)) moved = pushed = true;
    if (!pushed) break;
  }
  if (!moved) return false;
  settle(state, group, s.displacement);
  if (!before_move) for_each_island(state, group, [&](std::size_t k, BodyRange bodies) { displace_island(state, k, bodies); });
  return true;
}

// The group's blocks — its contacts, then its limit rows — their rows and half rows through the
// factor of H at the current q (its islands' part), the contacts' K, the limit rows' Delassus
// matrix per island, approach speeds and e = 0 for resting contacts. False, with the group's v
// not finite, when H was not positive definite.
bool prepare_group(FeatherstoneState& state, const ConstraintGroup& group, double dt) {
  JointSpaceContactScratch& s = state.contact;
  bool factored = true;
  for_each_island(state, group, [&](std::size_t k, BodyRange bodies) {
    if (s.factored[k]) return;  // the velocity update's, at these poses
    factor_island(state, k, bodies, constraints_before_move(state) ? state.controls.armature.data() : nullptr);
    factored = s.factored[k] && factored;
  });
  if (!factored) {
    // H is positive definite at any finite pose; it is not only once the state has gone
    // non-finite. Say so through v, which the step's status checks, instead of answering the
    // contacts with a broken factor.
    for_each_island(state, group, [&](std::size_t k, BodyRange) {
      const auto [first, last] = island_velocities(state, k);
      state.v.segment(first, last - first).setConstant(std::numeric_limits<double>::quiet_NaN());
    });
    return false;
  }
  std::vector<int>& path = s.island_scratch[static_cast<std::size_t>(s.group_island[static_cast<std::size_t>(group.first_island)])].path;
  for (int block = group.first_block; block < group.first_row_block; ++block) {
    const auto g = static_cast<std::size_t>(block);
    RigidContact& contact = state.contacts[static_cast<std::size_t>(s.block_source[g])];
    contact_rows(state, g, contact);
    s.contact_matrix[g] = half_rows(s, g, path, /*one_column=*/false);
    s.free_motion[g] = block_motion(s, g, state.v);
    record_approach(contact, -s.free_motion[g][0], state.settings, dt);
  }
  for (int block = group.first_row_block; block < group.last_block; ++block) {
    const auto g = static_cast<std::size_t>(block);
    JointLimitRow& row = state.controls.rows[static_cast<std::size_t>(s.block_source[g])];
    limit_row_entries(state, g, row);
    row.inverse_mass = half_rows(s, g, path, /*one_column=*/true)(0, 0);
  }
  form_limit_delassus(state, group);
  return true;
}

// One group, whole: its impulses, then (`push`) its push-out, and its rigid bodies refreshed. The
// passes leave state.kinematics' poses those of q (the push-out's, with its velocities, when it
// moved q): the rigid bodies need only the new velocities.
void solve_group(FeatherstoneState& state, ConstraintGroup& group, double dt, bool push) {
  group.pushed = false;
  if (!prepare_group(state, group, dt)) return;
  impulse_passes(state, group, dt);
  const bool moved = push && push_out(state, group, dt);
  if (constraints_before_move(state)) {
    group.pushed = moved;
    return;  // advance_positions moves the group's islands and refreshes their rigid bodies
  }
  for_each_island(state, group, [&](std::size_t, BodyRange bodies) {
    if (!moved) body_velocities(state.tree, state.v, state.kinematics, bodies);
    mirror_rigid_bodies(state, bodies);
  });
}

// --- Groups --------------------------------------------------------------------------------------

// The root of island k's set (union–find with path halving).
std::int32_t set_of(std::vector<std::int32_t>& link, std::int32_t k) {
  while (link[static_cast<std::size_t>(k)] != k) {
    link[static_cast<std::size_t>(k)] = link[static_cast<std::size_t>(link[static_cast<std::size_t>(k)])];
    k = link[static_cast<std::size_t>(k)];
  }
  return k;
}

// Block g's entries: the coordinates of its bodies' paths to the root.
int block_entries(const FeatherstoneState& state, std::size_t g, bool contact) {
  const JointSpaceContactScratch& s = state.contact;
  const auto length = [&](std::int32_t tree_body) { return s.path_length[static_cast<std::size_t>(tree_body)]; };
  const auto source = static_cast<std::size_t>(s.block_source[g]);
  if (!contact) return length(state.controls.rows[source].body);
  const RigidContact& c = state.contacts[source];
  return length(state.tree_body[c.a]) + (c.b >= 0 ? length(state.tree_body[c.b]) : 0);
}

// The islands each group holds (ascending), and how many contacts, limit rows and islands with
// limit rows; the groups in the order of their first islands.
void find_groups(FeatherstoneState& state) {
  JointSpaceContactScratch& s = state.contact;
  const auto islands = static_cast<std::int32_t>(state.islands.size());
  for (std::int32_t k = 0; k < islands; ++k) {
    s.island_link[static_cast<std::size_t>(k)] = k, s.island_group[static_cast<std::size_t>(k)] = -1;
    s.island_rows[static_cast<std::size_t>(k)] = 0;
  }
  constexpr std::int32_t kTouched = -2;  // an island with a contact or a limit row, not yet in a group
  for (const RigidContact& contact : state.contacts) {
    const auto a = static_cast<std::int32_t>(state.island_of_body[contact.a]);
    s.island_group[static_cast<std::size_t>(a)] = kTouched;
    if (contact.b < 0) continue;
    const auto b = static_cast<std::int32_t>(state.island_of_body[contact.b]);
    s.island_group[static_cast<std::size_t>(b)] = kTouched;
    s.island_link[static_cast<std::size_t>(set_of(s.island_link, a))] = set_of(s.island_link, b);
  }
  for (const JointLimitRow& row : state.controls.rows) {
    s.island_group[static_cast<std::size_t>(row.island)] = kTouched;
    ++s.island_rows[static_cast<std::size_t>(row.island)];
  }
  s.groups.clear();
  for (std::int32_t k = 0; k < islands; ++k) {
    const auto index = static_cast<std::size_t>(k);
    if (s.island_group[index] == -1) continue;
    const auto root = static_cast<std::size_t>(set_of(s.island_link, k));
    if (s.island_group[root] < 0) {  // the set's first island
      s.island_group[root] = static_cast<std::int32_t>(s.groups.size());
      s.groups.emplace_back();
    }
    s.island_group[index] = s.island_group[root];
    ConstraintGroup& group = s.groups[static_cast<std::size_t>(s.island_group[index])];
    ++group.last_island;
    group.last_block += s.island_rows[index];  // counts for now (lay_out_groups)
    if (s.island_rows[index] > 0) ++group.last_limit;
  }
  for (const RigidContact& contact : state.contacts) {
    ++s.groups[static_cast<std::size_t>(s.island_group[state.island_of_body[contact.a]])].first_row_block;  // a count, too
  }
}

// The groups' islands, blocks (contacts, then limit rows island by island) and limit matrices
// laid out group after group, from find_groups' counts.
void lay_out_groups(FeatherstoneState& state) {
  JointSpaceContactScratch& s = state.contact;
  int islands = 0, blocks = 0, limits = 0;
  for (ConstraintGroup& group : s.groups) {
    const int count = group.last_island, contacts = group.first_row_block, rows = group.last_block, with_rows = group.last_limit;
    group.first_island = group.last_island = islands;
    islands += count;
    group.first_block = group.last_block = blocks, group.first_row_block = blocks + contacts;
    blocks += contacts + rows;
    group.first_limit = group.last_limit = limits;
    limits += with_rows;
  }
  s.group_island.resize(static_cast<std::size_t>(islands));
  s.block_source.resize(static_cast<std::size_t>(blocks));
  s.limit_islands.resize(static_cast<std::size_t>(limits));
  // last_island, last_block and last_limit are the cursors: each ends where its group does.
  for (std::size_t k = 0; k < s.island_group.size(); ++k) {
    if (s.island_group[k] >= 0) s.group_island[static_cast<std::size_t>(s.groups[static_cast<std::size_t>(s.island_group[k])].last_island++)] = static_cast<std::int32_t>(k);
  }
  for (std::size_t c = 0; c < state.contacts.size(); ++c) {
    ConstraintGroup& group = s.groups[static_cast<std::size_t>(s.island_group[state.island_of_body[state.contacts[c].a]])];
    s.block_source[static_cast<std::size_t>(group.last_block++)] = static_cast<std::int32_t>(c);
  }
  std::size_t matrix = 0;
  for (ConstraintGroup& group : s.groups) {
    for (int n = group.first_island; n < group.last_island; ++n) {
      const std::int32_t k = s.group_island[static_cast<std::size_t>(n)];
      const int rows = s.island_rows[static_cast<std::size_t>(k)];
      if (rows == 0) continue;
      s.limit_islands[static_cast<std::size_t>(group.last_limit++)] = {k, group.last_block, rows, matrix};
      s.island_cursor[static_cast<std::size_t>(k)] = group.last_block;
      group.last_block += rows;
      matrix += static_cast<std::size_t>(rows) * static_cast<std::size_t>(rows);
    }
  }
  for (std::size_t r = 0; r < state.controls.rows.size(); ++r) {
    s.block_source[static_cast<std::size_t>(s.island_cursor[static_cast<std::size_t>(state.controls.rows[r].island)]++)] = static_cast<std::int32_t>(r);
  }
  s.limit_matrix.resize(matrix);  // within what compile reserved, unless the rows grew past it
}

// The step's groups (ConstraintGroup) and the room of their blocks' rows; false when there is
// nothing to solve.
bool form_groups(FeatherstoneState& state) {
  JointSpaceContactScratch& s = state.contact;
  if (state.contacts.empty() && state.controls.rows.empty()) return false;
  find_groups(state);
  lay_out_groups(state);
  const std::size_t blocks = s.block_source.size();
  s.row_begin.resize(blocks + 1);
  s.row_begin[0] = 0;
  for (const ConstraintGroup& group : s.groups) {
    for (int g = group.first_block; g < group.last_block; ++g) {
      const auto index = static_cast<std::size_t>(g);
      s.row_begin[index + 1] = s.row_begin[index] + block_entries(state, index, g < group.first_row_block);
    }
  }
  const auto entries = static_cast<std::size_t>(s.row_begin[blocks]);
  s.row_coordinate.resize(entries), s.row_value.resize(entries);
  s.half_coordinate.resize(entries), s.half_value.resize(entries);
  s.half_end.resize(blocks), s.contact_matrix.resize(blocks), s.free_motion.resize(blocks), s.push.resize(blocks), s.impulse.resize(blocks);
  return true;
}

// --- Warm start ----------------------------------------------------------------------------------

// Each contact's warm start into s.impulse (ContactMemory::take), each limit row's likewise: the
// last step's impulse of the row with its key.
void warm_start(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.memory.begin_matching();
  for (const ConstraintGroup& group : s.groups) {
    for (int g = group.first_block; g < group.first_row_block; ++g) {
      s.impulse[static_cast<std::size_t>(g)] = s.memory.take(state.contacts[static_cast<std::size_t>(s.block_source[static_cast<std::size_t>(g)])], dt);
    }
  }
  // The limit rows: both lists ascend by key.
  auto last = s.remembered_rows.begin();
  for (JointLimitRow& row : state.controls.rows) {
    while (last != s.remembered_rows.end() && last->first < row.key) ++last;
    row.impulse = last != s.remembered_rows.end() && last->first == row.key ? s.memory.scale(dt) * last->second : 0.0;
  }
}

// The step's contact and limit-row impulses as the next step's warm start (in the groups' order,
// which no thread count changes).
void remember_impulses(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.memory.begin_recording();
  for (const ConstraintGroup& group : s.groups) {
    for (int g = group.first_block; g < group.first_row_block; ++g) {
      s.memory.record(state.contacts[static_cast<std::size_t>(s.block_source[static_cast<std::size_t>(g)])], s.impulse[static_cast<std::size_t>(g)]);
    }
  }
  s.memory.finish_recording(dt);
  s.recording_rows.clear();
  for (const JointLimitRow& row : state.controls.rows) {
    if (row.impulse > 0) s.recording_rows.emplace_back(row.key, row.impulse);
  }
  std::swap(s.remembered_rows, s.recording_rows);
}

// Every group, on the state's threads when it has them and more than one group; the limit rows
// those that may act within the step at v or at `also`.
void solve_groups(FeatherstoneState& state, double dt, bool push, const Eigen::VectorXd* also = nullptr) {
  find_limit_rows(state, dt, also);
  JointSpaceContactScratch& s = state.contact;
  if (!form_groups(state)) {
    s.groups.clear();  // advance_positions reads no island's group
    return;
  }
  if (s.factor.size() != state.tree.velocity_count()) s.factor.assign(state.tree);  // a large tree's first use (compile.cpp)
  warm_start(state, dt);
  run_stage(state.runner.get(), s.groups.size(), [&](std::size_t g) { solve_group(state, s.groups[g], dt, push); });
}

}  // namespace

void apply_joint_space_impulses(FeatherstoneState& state, double dt) {
  std::fill(state.contact.factored.begin(), state.contact.factored.end(), 0);
  solve_groups(state, dt, /*push=*/false);
}

void resolve_joint_space_contacts(FeatherstoneState& state, double dt) {
  if (!constraints_before_move(state)) {
    solve_groups(state, dt, /*push=*/true);
    remember_impulses(state, dt);
    return;
  }
  // Before the move no push-out follows the positions: a limit the rows left out because v did
  // not approach it, which the impulses then drive the joint through, would be crossed by the
  // move. So when the constrained velocity reaches rows the free one did not, the step is solved
  // again from the free velocity with those rows too (an impact's step; rarely twice a second).
  JointSpaceContactScratch& s = state.contact;
  s.free_velocity = state.v;
  solve_groups(state, dt, /*push=*/true);
  const auto rows = static_cast<int>(state.controls.rows.size());
  if ((rows > 0 || !state.contacts.empty()) && find_limit_rows(state, dt, &s.free_velocity, /*count_only=*/true) != rows) {
    s.constrained_velocity = state.v;
    state.v = s.free_velocity;
    solve_groups(state, dt, /*push=*/true, &s.constrained_velocity);
  }
  remember_impulses(state, dt);
}

void factored_forward_dynamics(FeatherstoneState& state, std::size_t island, const Eigen::VectorXd& joint_forces, const double* armature,
                               Eigen::VectorXd& accelerations) {
  JointSpaceContactScratch& s = state.contact;
  const BodyRange bodies = island_bodies(state, island);
  const auto [first, last] = island_velocities(state, island);
  factor_island(state, island, bodies, armature);
  bias_forces(state.tree, state.kinematics, state.settings.gravity, s.composite, accelerations, bodies);
  auto on_island = accelerations.segment(first, last - first);
  on_island = joint_forces.segment(first, last - first) - on_island;
  if (!s.factored[island]) {
    on_island.setConstant(std::numeric_limits<double>::quiet_NaN());  // the step's status reports it
    return;
  }
  s.factor.solve(accelerations, first, last);
}

void advance_positions(FeatherstoneState& state, std::size_t island) {
  JointSpaceContactScratch& s = state.contact;
  const BodyRange bodies = island_bodies(state, island);
  semi_implicit_move(state.tree, state.q, state.v, state.last_substep[island], state.integration.stage_displacement, bodies);
  const std::int32_t group = s.groups.empty() ? -1 : s.island_group[island];
  if (group >= 0 && s.groups[static_cast<std::size_t>(group)].pushed) {
    body_poses(state.tree, state.q, state.kinematics, bodies);
    displace_island(state, island, bodies);
  } else {
    forward_kinematics(state.tree, state.q, state.v, state.kinematics, bodies);
  }
  mirror_rigid_bodies(state, bodies);
}

}  // namespace limber
