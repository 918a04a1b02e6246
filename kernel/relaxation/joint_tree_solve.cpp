#include "limber/kernel/relaxation/joint_trees.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/relaxation/joint_projection.hpp"
#include "limber/kernel/relaxation/joint_tree_limbs.hpp"
#include "limber/kernel/relaxation/tree_contacts.hpp"
#include "limber/kernel/relaxation/tree_packs.hpp"

// Solving the joint trees each sweep: the limbs loaded as rigid bodies, the joints assembled,
// factored and solved by the tree elimination in SIMD lanes across components of one shape
// (tree_packs.hpp), the limbs moved; Newton steps, and rounds with the contacts
// (tree_contacts.hpp); packs as tasks.
namespace limber {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using joint_tree_limbs::kSide;
using joint_tree_limbs::limb_particles;
using joint_tree_limbs::limb_pose;
using joint_tree_limbs::LimbPose;

Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

// An angle limit (swing, twist, hinge range) measured by the sweeps' own formulas
// (joint_projection::measure) on the two limbs' frames: the angle and the axis B turns about.
joint_projection::Measure<double> measure_limit(const JointTrees& trees, std::size_t slot, const Eigen::Matrix3d& a,
                                                const Eigen::Matrix3d& b) {
  using Vec = joint_projection::Vec3<double>;
  const auto vec = [](const Eigen::Vector3d& x) { return Vec{x.x(), x.y(), x.z()}; };
  return joint_projection::measure<ScalarLanes<double>, double>(trees.limit_kind[slot], trees.limits, slot, vec(a.col(0)), vec(a.col(1)),
                                                                vec(a.col(2)), vec(b.col(0)), vec(b.col(1)), vec(b.col(2)));
}

// Angle at which a reached limit counts as reached in the velocity stage, rad.
constexpr double kLimitReached = 1e-6;

// Rigid-body data of a limb: its mass, centre, inertia and frame, into the scratch. With
// `rigidify` (the position stage) its particles are first put back on its rest shape at its
// current pose (centre of mass kept, frame from head, tail, F⁺, F⁻): for the solve a limb is a
// rigid body, and what the sweeps and contacts did to its shape is undone here, as rigid
// bodies' solvers do (its own constraints are then the tree's, not the sweeps').
template <typename Scalar>
void load_limb(VerletState<Scalar>& state, JointTrees& trees, std::size_t limb, bool rigidify) {
  Eigen::Vector3d x[kSide];
  double mass[kSide], total = 0;
  const int n = limb_particles(state, trees, limb, x, mass);
  const bool framed = trees.limb_framed[limb];
  const LimbPose pose = limb_pose(x, mass, n, framed);
  for (int k = 0; k < n; ++k) {
    total += mass[k];
    if (!rigidify) continue;
    const Eigen::Vector3d& rest = trees.rest_offset[limb][static_cast<std::size_t>(k)];
    x[k] = pose.centre + (framed ? Eigen::Vector3d(pose.frame * rest) : Eigen::Vector3d(rest.z() * pose.frame.col(2)));
    state.particles.set_position(trees.limb_particles[limb][static_cast<std::size_t>(k)], x[k].template cast<Scalar>());
  }
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  double second_moment = 0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d r = x[k] - pose.centre;
    inertia += mass[k] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    second_moment += mass[k] * r.squaredNorm();
  }
  const Eigen::Vector3d u = pose.frame.col(2);
  if (!framed) inertia += second_moment * u * u.transpose();  // the spin a stick cannot have: never excited
  trees.centre[limb] = pose.centre, trees.frame[limb] = pose.frame;
  trees.mass[limb] = total, trees.inertia[limb] = inertia;
}

// Writes joint j's J blocks into the scratch (block_a, block_b: the pack gathers them),
// its active limits into trees.active_limits[j] (the limits reached: violated, or in the
// velocity stage at their bound and turning past it; bit k for limit k) and returns its rows'
// C (position level; a limit's C is its violation).
template <typename Scalar>
Vector6 assemble_joint(const VerletState<Scalar>& state, JointTrees& trees, std::size_t j, bool velocities) {
  const JointTrees::Joint& joint = trees.joints[j];
  Matrix6& block_a = trees.block_a[j];
  Matrix6& block_b = trees.block_b[j];
  block_a.setZero(), block_b.setZero();
  Vector6 c = Vector6::Zero();
  int row = 0;
  if (joint.point) {
    const std::uint32_t null_particle = state.particles.null_particle();
    Eigen::Vector3d value = Eigen::Vector3d::Zero();
    for (int side = 0; side < 2; ++side) {
      const std::int32_t limb = side == 0 ? joint.limb_a : joint.limb_b;
      double sum = 0;
      Eigen::Vector3d lever = Eigen::Vector3d::Zero();
      for (int k = side * kSide; k < (side + 1) * kSide && joint.particle[k] != null_particle; ++k) {
        const Eigen::Vector3d x = state.particles.position(joint.particle[k]).template cast<double>();
        value += joint.coefficient[k] * x;
        if (limb >= 0) sum += joint.coefficient[k], lever += joint.coefficient[k] * (x - trees.centre[limb]);
      }
      if (limb < 0) continue;
      Matrix6& block = side == 0 ? block_a : block_b;
      block.block<3, 3>(0, 0) = sum * Eigen::Matrix3d::Identity();
      block.block<3, 3>(0, 3) = -skew(lever);
    }
    c.head<3>() = value;
    row = 3;
  }
  if (joint.align_row >= 0) {
    const Eigen::Matrix3d frame_a = joint.limb_a >= 0 ? trees.frame[joint.limb_a] : Eigen::Matrix3d::Identity();
    const Eigen::Vector3d e = trees.frame[joint.limb_b] * joint.e;
    for (const Eigen::Vector3d& t_local : {joint.t1, joint.t2}) {
      const Eigen::Vector3d t = frame_a * t_local;
      c[row] = t.dot(e);
      block_a.block<1, 3>(row, 3) = t.cross(e).transpose(), block_b.block<1, 3>(row, 3) = e.cross(t).transpose();
      ++row;
    }
  }
  std::uint8_t active_limits = 0, limit_upper = 0;
  for (std::size_t k = 0; k < joint.limit.size(); ++k) {
    const std::int32_t slot = joint.limit[k];
    if (slot < 0) continue;
    const Eigen::Matrix3d frame_a = joint.limb_a >= 0 ? trees.frame[joint.limb_a] : Eigen::Matrix3d::Identity();
    const auto [angle, axis_lanes] = measure_limit(trees, static_cast<std::size_t>(slot), frame_a, trees.frame[joint.limb_b]);
    const Eigen::Vector3d axis(axis_lanes.x, axis_lanes.y, axis_lanes.z);
    const double lower = trees.limits.lower[slot], upper = trees.limits.upper[slot];
    const double violation = angle - std::clamp(angle, lower, upper);
    // Held (the call's last Newton step had it active and pushing): it stays a row, holding its
    // angle where it is (C = 0) while inside, so that the active set does not flip every step.
    const bool held_upper = trees.limit_held[j] & (1u << (2 * k)), held_lower = trees.limit_held[j] & (1u << (2 * k + 1));
    bool active = violation != 0 || held_upper || held_lower;
    const bool at_upper = violation > 0 || (violation == 0 && held_upper);
    if (velocities) {
      Eigen::Vector3d turn = trees.rate[static_cast<std::size_t>(joint.limb_b)].tail<3>();
      if (joint.limb_a >= 0) turn -= trees.rate[static_cast<std::size_t>(joint.limb_a)].tail<3>();
      const double rate = axis.dot(turn);
      active = (angle >= upper - kLimitReached && rate > 0) || (angle <= lower + kLimitReached && rate < 0);
    }
    const int limit_row = joint.limit_row(k);
    if (!active || limit_row < 0) continue;  // an idle limit's row stays decoupled (JointTrees::Joint::fixed_rows)
    active_limits |= static_cast<std::uint8_t>(1u << k);
    if (at_upper) limit_upper |= static_cast<std::uint8_t>(1u << k);
    c[limit_row] = violation;
    block_a.block<1, 3>(limit_row, 3) = -axis.transpose(), block_b.block<1, 3>(limit_row, 3) = axis.transpose();
  }
  trees.active_limits[j] = active_limits;
  trees.limit_upper[j] = limit_upper;
  return c;
}

// After a position solve: each active limit whose multiplier pushes (μ > 0 at an upper bound,
// μ < 0 at a lower, as M·Δq = −Jᵀμ) is held at the call's next Newton step (assemble_joint).
void hold_pushing_limits(JointTrees& trees, const TreeOrdering::Component& component) {
  const auto& order = trees.elimination.ordering().order;
  const std::int32_t limbs = trees.elimination.body_count();
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    if (order[k] < limbs) continue;
    const auto j = static_cast<std::size_t>(order[k] - limbs);
    const JointTrees::Joint& joint = trees.joints[j];
    std::uint8_t held = 0;
    for (std::size_t l = 0; l < joint.limit.size(); ++l) {
      if (!(trees.active_limits[j] & (1u << l))) continue;
      const double mu = trees.elimination.work(static_cast<std::size_t>(order[k]))(joint.limit_row(l));
      const bool upper = trees.limit_upper[j] & (1u << l);
      if (upper ? mu > 0 : mu < 0) held |= static_cast<std::uint8_t>(1u << (2 * l + (upper ? 0 : 1)));
    }
    trees.limit_held[j] = held;
  }
}

// Stages one component's system (tree_packs.hpp gathers it), its limbs and joints loaded at the
// current positions: each limb's mass and inertia, each joint's J blocks and active limits, and
// work(limb) = 0 and work(joint) = −C (positions), or −J·(v, ω) with each limb's rigid velocity
// (velocities: v of its centre, ω = I⁻¹ Σ m r × v, kept in trees.rate, and the particles set to
// it). Every limb block is positive definite (positive masses; a stick's spin regularized), so a
// factor cannot fail.
template <typename Scalar>
void stage_component(VerletState<Scalar>& state, JointTrees& trees, std::uint32_t index, bool velocities) {
  const TreeOrdering::Component& component = trees.elimination.ordering().components[index];
  const auto& order = trees.elimination.ordering().order;
  const std::int32_t limbs = trees.elimination.body_count();
  const std::uint32_t null_particle = state.particles.null_particle();
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    if (order[k] >= limbs) continue;
    const auto limb = static_cast<std::size_t>(order[k]);
    load_limb(state, trees, limb, !velocities);
    if (!velocities) continue;
    Eigen::Vector3d momentum = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    for (const std::uint32_t p : trees.limb_particles[limb]) {
      if (p == null_particle) break;
      const double mass = 1.0 / static_cast<double>(state.particles.inverse_mass[p]);
      const Eigen::Vector3d v = state.particles.velocity(p).template cast<double>();
      momentum += mass * v;
      angular += mass * (state.particles.position(p).template cast<double>() - trees.centre[limb]).cross(v);
    }
    trees.rate[limb].head<3>() = momentum / trees.mass[limb];
    trees.rate[limb].tail<3>() = trees.inertia[limb].ldlt().solve(angular);
    // The particles move with the limb: its rigid velocity, which keeps P and L.
    for (const std::uint32_t p : trees.limb_particles[limb]) {
      if (p == null_particle) break;
      const Eigen::Vector3d r = state.particles.position(p).template cast<double>() - trees.centre[limb];
      const Eigen::Vector3d v = trees.rate[limb].head<3>() + trees.rate[limb].tail<3>().cross(r);
      state.particles.set_velocity(p, v.template cast<Scalar>());
    }
  }
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    const std::int32_t node = order[k];
    if (node < limbs) {
      trees.elimination.work(static_cast<std::size_t>(node)).setZero();
      continue;
    }
    const auto j = static_cast<std::size_t>(node - limbs);
    const Vector6 c = assemble_joint(state, trees, j, velocities);
    Vector6& rhs = trees.elimination.work(static_cast<std::size_t>(node));
    if (!velocities) {
      rhs = -c;
      continue;
    }
    const JointTrees::Joint& joint = trees.joints[j];
    rhs = -(trees.block_b[j] * trees.rate[static_cast<std::size_t>(joint.limb_b)]);
    if (joint.limb_a >= 0) rhs -= trees.block_a[j] * trees.rate[static_cast<std::size_t>(joint.limb_a)];
  }
}

// Calls visit(limb) for every limb of `component`.
template <typename Visit>
void for_each_limb(const JointTrees& trees, const TreeOrdering::Component& component, Visit&& visit) {
  const auto& order = trees.elimination.ordering().order;
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    if (order[k] < trees.elimination.body_count()) visit(static_cast<std::size_t>(order[k]));
  }
}

// Moves limb `limb` of a solved component rigidly by work(limb) = (Δp, Δφ): the exact rotation
// R(Δφ) about its centre. Returns the largest particle displacement, m.
template <typename Scalar>
double move_limb(VerletState<Scalar>& state, const JointTrees& trees, std::size_t limb) {
  const Vector6& move = trees.elimination.work(limb);
  const Eigen::Vector3d turn = move.tail<3>();
  const double angle = turn.norm();
  const Eigen::Matrix3d rotation = angle > 0 ? Eigen::AngleAxisd(angle, turn / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  const Eigen::Vector3d& centre = trees.centre[limb];
  double largest = 0;
  for (const std::uint32_t p : trees.limb_particles[limb]) {
    if (p == state.particles.null_particle()) break;
    const Eigen::Vector3d x = state.particles.position(p).template cast<double>();
    const Eigen::Vector3d moved = centre + move.head<3>() + rotation * (x - centre);
    largest = std::max(largest, (moved - x).norm());
    state.particles.set_position(p, moved.template cast<Scalar>());
  }
  return largest;
}

}  // namespace

// Newton steps a tree takes in one call at most, and the largest move after which it takes
// another, from a fresh factor: a Newton move δ on a lever r leaves about δ²/r (1e-5 m on
// 0.1 m: 1e-9 m). Every step factors afresh (a kept factor would have to be chosen lane by lane).
constexpr int kNewtonSteps = 4;
constexpr double kNewtonMove = 1e-5;
// The same for a round with contacts (tree_contacts.hpp), whose Jacobi pushes converge linearly,
// not quadratically: a round moving no particle by 5e-5 m (a tenth of a millimetre, against a
// goal of a centimetre's penetration) ends the call. On the pile and the rain at 2 × 2 and
// 4 × 1 this ran 1.4× as many steps a second as 1e-5 m, at the same penetration (bench/ragdolls.md,
// "Exact limits and contacts with the trees"); what it leaves of the joints, ~(5e-5)²/0.1 m, is
// rounding.
constexpr double kContactRoundMove = 5e-5;
// Jacobi iterations of the contacts in a round, each a back-substitution with the round's factor
// (no new factor): four brought the pile's penetration at 2 × 2 from 1 cm to 2 mm at the same
// steps a second (fewer rounds), and let a ragdoll lying across another come to rest.
constexpr int kContactIterations = 4;

template <typename Scalar>
void begin_joint_trees(VerletState<Scalar>& state, double dt) {
  JointTrees& trees = state.plan.joint_trees;
  StageClock clock(state.options.profile);
  gather_tree_contacts(state, dt);
  std::fill(trees.counts.begin(), trees.counts.end(), JointTreeCounts{});
  for (TreePack<Scalar>& pack : trees.packs->packs<Scalar>()) pack.factors = 0, pack.seconds = {};
  trees.contact_seconds = clock.lap();
}

template <typename Scalar>
JointTreeCounts joint_tree_counts(const VerletState<Scalar>& state) {
  const JointTrees& trees = state.plan.joint_trees;
  JointTreeCounts counts;
  for (const JointTreeCounts& component : trees.counts) counts += component;
  for (const TreePack<Scalar>& pack : trees.packs->packs<Scalar>()) {
    counts.lane_slots += pack.factors * static_cast<int>(kTreeLanes<Scalar>);
    counts.seconds += pack.seconds;
  }
  counts.seconds.contacts += trees.contact_seconds;
  return counts;
}

namespace {

// Moves every limb of component `index` by its work(); returns the largest particle move, m.
template <typename Scalar>
double move_component(VerletState<Scalar>& state, std::uint32_t index) {
  const JointTrees& trees = state.plan.joint_trees;
  double moved = 0;
  for_each_limb(trees, trees.elimination.ordering().components[index], [&](std::size_t limb) { moved = std::max(moved, move_limb(state, trees, limb)); });
  return moved;
}

// Forgets the limits held in component `index`'s last call (hold_pushing_limits).
void release_limits(JointTrees& trees, std::uint32_t index) {
  const TreeOrdering::Component& component = trees.elimination.ordering().components[index];
  const auto& order = trees.elimination.ordering().order;
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    if (order[k] >= trees.elimination.body_count()) trees.limit_held[static_cast<std::size_t>(order[k] - trees.elimination.body_count())] = 0;
  }
}

// Which of a pack's awake components a stage works on.
enum class Lanes { awake, without_contacts, with_contacts_unsettled };

// The lanes of `pack` whose components are awake and, for `which`, have no contacts this
// substep, or have some and are not settled.
template <typename Number>
LaneMask lanes_of(const JointTrees& trees, const TreePack<Number>& pack, Lanes which) {
  LaneMask lanes{};
  for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
    const std::int32_t c = pack.component[lane];
    if (c < 0 || !trees.component_awake[static_cast<std::size_t>(c)]) continue;
    const auto index = static_cast<std::uint32_t>(c);
    const bool has_contacts = !trees.contacts.empty() && !trees.component_contacts.row(index).empty();
    switch (which) {
      case Lanes::awake: lanes[lane] = true; break;
      case Lanes::without_contacts: lanes[lane] = !has_contacts; break;
      case Lanes::with_contacts_unsettled: lanes[lane] = has_contacts && !trees.settled[index]; break;
    }
  }
  return lanes;
}

bool any_lane(const LaneMask& lanes) { return std::find(lanes.begin(), lanes.end(), true) != lanes.end(); }

// Calls visit(component) for the component of each lane where `lanes` holds.
template <typename Number, typename Visit>
void for_each_lane(const TreePack<Number>& pack, const LaneMask& lanes, Visit&& visit) {
  for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
    if (lanes[lane]) visit(static_cast<std::uint32_t>(pack.component[lane]));
  }
}

// A Newton step of the joints of `pack`'s lanes where `lanes` holds: staged, factored and solved
// side by side (with `mobility`, each limb's block of the inverse too), the limits that push held.
template <typename Scalar>
void newton_step(VerletState<Scalar>& state, TreePack<Scalar>& pack, const LaneMask& lanes, bool mobility) {
  JointTrees& trees = state.plan.joint_trees;
  StageClock clock(state.options.profile);
  for_each_lane(pack, lanes, [&](std::uint32_t c) { stage_component(state, trees, c, false); });
  pack.seconds.staging += clock.lap();
  eliminate_pack(trees, pack, lanes, mobility);
  pack.seconds.elimination += clock.lap();
  for_each_lane(pack, lanes, [&](std::uint32_t c) {
    JointTreeCounts& counts = trees.counts[c];
    ++counts.factors, ++counts.substitutions, ++counts.newton_steps;
    counts.inverse_diagonals += mobility ? 1 : 0;
    hold_pushing_limits(trees, trees.elimination.ordering().components[c]);
  });
  pack.seconds.staging += clock.lap();
}

// The components without contacts, on the positions: Newton steps until a step moves no particle
// of that component by kNewtonMove (at most kNewtonSteps); a lane that has converged drops out
// of the next. Returns the largest move, m.
template <typename Scalar>
double pack_positions(VerletState<Scalar>& state, TreePack<Scalar>& pack) {
  JointTrees& trees = state.plan.joint_trees;
  LaneMask running = lanes_of(trees, pack, Lanes::without_contacts);
  for_each_lane(pack, running, [&](std::uint32_t c) { ++trees.counts[c].solves, release_limits(trees, c); });
  double largest = 0;
  for (int newton = 0; newton < kNewtonSteps && any_lane(running); ++newton) {
    newton_step(state, pack, running, false);
    StageClock clock(state.options.profile);
    for (std::size_t lane = 0; lane < kTreeLanes<Scalar>; ++lane) {
      if (!running[lane]) continue;
      const auto c = static_cast<std::uint32_t>(pack.component[lane]);
      const double moved = move_component(state, c);
      largest = std::max(largest, moved);
      running[lane] = moved >= kNewtonMove;
      if (running[lane] && newton == kNewtonSteps - 1) ++trees.counts[c].capped;
    }
    pack.seconds.moves += clock.lap();
  }
  return largest;
}

// A round of the components with contacts (tree_contacts.hpp), stage 1: a Newton step of their
// joints, solved but not applied (JointTrees::joint_motion), with each limb's mobility.
template <typename Scalar>
double contact_round_joints(VerletState<Scalar>& state, TreePack<Scalar>& pack, int round) {
  JointTrees& trees = state.plan.joint_trees;
  const LaneMask lanes = lanes_of(trees, pack, Lanes::with_contacts_unsettled);
  if (!any_lane(lanes)) return 0;
  if (round == 0) for_each_lane(pack, lanes, [&](std::uint32_t c) { ++trees.counts[c].solves, release_limits(trees, c); });
  newton_step(state, pack, lanes, true);
  // The loops' mobilities are path solves: elimination.
  StageClock clock(state.options.profile);
  for_each_lane(pack, lanes, [&](std::uint32_t c) {
    for_each_limb(trees, trees.elimination.ordering().components[c], [&](std::size_t limb) {
      trees.joint_motion[limb] = trees.elimination.work(limb);
      trees.load_motion[limb].setZero();
    });
  });
  take_loop_mobilities(state, pack, lanes);
  pack.seconds.elimination += clock.lap();
  return 0;
}

// Stage 3 of a round's iteration: the contacts' loads solved with the round's factor, their
// motion scaled so that no contact overshoots and added to the round's (load_motion).
template <typename Scalar>
double contact_iteration_loads(VerletState<Scalar>& state, TreePack<Scalar>& pack) {
  JointTrees& trees = state.plan.joint_trees;
  StageClock clock(state.options.profile);
  LaneMask lanes = lanes_of(trees, pack, Lanes::with_contacts_unsettled);
  for (std::size_t lane = 0; lane < kTreeLanes<Scalar>; ++lane) {
    const std::int32_t c = pack.component[lane];
    if (c >= 0) trees.load_scale[static_cast<std::size_t>(c)] = 1;
    if (!lanes[lane]) continue;
    const auto index = static_cast<std::uint32_t>(c);
    const TreeOrdering::Component& component = trees.elimination.ordering().components[index];
    for (std::uint32_t k = component.begin; k < component.end; ++k) trees.elimination.work(static_cast<std::size_t>(trees.elimination.ordering().order[k])).setZero();
    lanes[lane] = add_tree_contact_loads(trees, index);
  }
  pack.seconds.contacts += clock.lap();
  if (!any_lane(lanes)) return 0;
  solve_pack(trees, pack, lanes);
  pack.seconds.elimination += clock.lap();
  for_each_lane(pack, lanes, [&](std::uint32_t c) {
    ++trees.counts[c].substitutions;
    const double scale = tree_contact_overshoot(trees, c);
    trees.load_scale[c] = scale;
    for_each_limb(trees, trees.elimination.ordering().components[c], [&](std::size_t limb) { trees.load_motion[limb] += trees.elimination.work(limb) / scale; });
  });
  pack.seconds.contacts += clock.lap();
  return 0;
}

// A round's end: each component moves by its joint step and its contacts' motion. It is settled
// when that moves no particle by kContactRoundMove.
template <typename Scalar>
double contact_round_move(VerletState<Scalar>& state, TreePack<Scalar>& pack, int round) {
  JointTrees& trees = state.plan.joint_trees;
  StageClock clock(state.options.profile);
  double largest = 0;
  for_each_lane(pack, lanes_of(trees, pack, Lanes::with_contacts_unsettled), [&](std::uint32_t c) {
    for_each_limb(trees, trees.elimination.ordering().components[c], [&](std::size_t limb) { trees.elimination.work(limb) = trees.joint_motion[limb] + trees.load_motion[limb]; });
    const double moved = move_component(state, c);
    largest = std::max(largest, moved);
    trees.settled[c] = moved < kContactRoundMove ? 1 : 0;
    if (!trees.settled[c] && round == kNewtonSteps - 1) ++trees.counts[c].capped;
  });
  pack.seconds.moves += clock.lap();
  return largest;
}

// After the rounds, the components they left unsettled take one more Newton step of their joints
// alone, so that every sweep still ends with the joints closed (its contacts' next sweep's).
template <typename Scalar>
double close_joints(VerletState<Scalar>& state, TreePack<Scalar>& pack) {
  JointTrees& trees = state.plan.joint_trees;
  const LaneMask lanes = lanes_of(trees, pack, Lanes::with_contacts_unsettled);
  if (!any_lane(lanes)) return 0;
  newton_step(state, pack, lanes, false);
  StageClock clock(state.options.profile);
  double largest = 0;
  for_each_lane(pack, lanes, [&](std::uint32_t c) { largest = std::max(largest, move_component(state, c)); });
  pack.seconds.moves += clock.lap();
  return largest;
}

// The awake components on the velocities; returns the largest |Δv|, m/s.
template <typename Scalar>
double pack_velocities(VerletState<Scalar>& state, TreePack<Scalar>& pack) {
  JointTrees& trees = state.plan.joint_trees;
  const std::uint32_t null_particle = state.particles.null_particle();
  const LaneMask lanes = lanes_of(trees, pack, Lanes::awake);
  if (!any_lane(lanes)) return 0;
  StageClock clock(state.options.profile);
  for_each_lane(pack, lanes, [&](std::uint32_t c) { stage_component(state, trees, c, true); });
  pack.seconds.staging += clock.lap();
  eliminate_pack(trees, pack, lanes);
  pack.seconds.elimination += clock.lap();
  double largest = 0;
  for_each_lane(pack, lanes, [&](std::uint32_t c) {
    ++trees.counts[c].factors, ++trees.counts[c].substitutions;
    for_each_limb(trees, trees.elimination.ordering().components[c], [&](std::size_t limb) {
      const Vector6& change = trees.elimination.work(limb);
      for (const std::uint32_t p : trees.limb_particles[limb]) {
        if (p == null_particle) break;
        const Eigen::Vector3d r = state.particles.position(p).template cast<double>() - trees.centre[limb];
        const Eigen::Vector3d dv = change.head<3>() + change.tail<3>().cross(r);
        largest = std::max(largest, dv.norm());
        state.particles.set_velocity(p, (state.particles.velocity(p).template cast<double>() + dv).template cast<Scalar>());
      }
    });
  });
  pack.seconds.moves += clock.lap();
  return largest;
}

// The stages as tasks, one a pack, on the relaxation's threads: packs share no component (and
// components no limb, particle, joint or node), so any split gives the same bits.
enum class TreeStage { positions, contact_joints, contact_loads, contact_move, close_joints, velocities };

template <typename Scalar>
struct PackStage {
  VerletState<Scalar>* state;
  TreeStage kind;
  int round = 0;
  static double run(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const PackStage*>(context);
    VerletState<Scalar>& state = *stage.state;
    TreePack<Scalar>& pack = state.plan.joint_trees.packs->template packs<Scalar>()[task];
    switch (stage.kind) {
      case TreeStage::positions: return pack_positions(state, pack);
      case TreeStage::contact_joints: return contact_round_joints(state, pack, stage.round);
      case TreeStage::contact_loads: return contact_iteration_loads(state, pack);
      case TreeStage::contact_move: return contact_round_move(state, pack, stage.round);
      case TreeStage::close_joints: return close_joints(state, pack);
      case TreeStage::velocities: return pack_velocities(state, pack);
    }
    return 0;
  }
};

template <typename Scalar>
double solve_packs(VerletState<Scalar>& state, TreeStage kind, int round = 0) {
  const PackStage<Scalar> stage{&state, kind, round};
  const std::size_t count = state.plan.joint_trees.packs->template packs<Scalar>().size();
  if (joint_trees_on_threads(state.plan) && count > 1) return state.plan.runner->run(count, &PackStage<Scalar>::run, &stage);
  double largest = 0;
  for (std::size_t task = 0; task < count; ++task) largest = std::max(largest, PackStage<Scalar>::run(&stage, task));
  return largest;
}

// Marks the components of the awake islands (JointTrees::component_awake).
template <typename Scalar>
void mark_awake_components(VerletState<Scalar>& state) {
  JointTrees& trees = state.plan.joint_trees;
  std::fill(trees.component_awake.begin(), trees.component_awake.end(), std::uint8_t{0});
  for (const std::uint32_t island : state.awake_islands) {
    for (const std::uint32_t index : trees.island_components.row(island)) trees.component_awake[index] = 1;
  }
}

}  // namespace

template <typename Scalar>
double project_joint_trees(VerletState<Scalar>& state) {
  JointTrees& trees = state.plan.joint_trees;
  if (!trees.active()) return 0.0;
  // The components without contacts first, in packs; then rounds of the stages of
  // tree_contacts.hpp (contacts between islands read both sides' steps), each a Newton step of
  // every component with contacts not yet settled, its contacts with it.
  mark_awake_components(state);
  double largest = solve_packs(state, TreeStage::positions);
  if (trees.contacts.empty()) return largest;
  std::fill(trees.settled.begin(), trees.settled.end(), std::uint8_t{0});
  for (int round = 0; round < kNewtonSteps; ++round) {
    largest = std::max(largest, solve_packs(state, TreeStage::contact_joints, round));
    for (int iteration = 0; iteration < kContactIterations; ++iteration) {
      StageClock clock(state.options.profile);
      tree_contact_impulses(state, iteration == 0);
      trees.contact_seconds += clock.lap();
      solve_packs(state, TreeStage::contact_loads, round);
    }
    largest = std::max(largest, solve_packs(state, TreeStage::contact_move, round));
    StageClock clock(state.options.profile);
    end_tree_contact_round(trees);
    trees.contact_seconds += clock.lap();
    bool settled = true;
    for (const std::uint32_t island : state.awake_islands) {
      for (const std::uint32_t index : trees.island_components.row(island)) {
        settled = settled && (trees.settled[index] || trees.component_contacts.row(index).empty());
      }
    }
    if (settled) return largest;
  }
  return std::max(largest, solve_packs(state, TreeStage::close_joints));
}

template <typename Scalar>
double project_joint_tree_velocities(VerletState<Scalar>& state) {
  if (!state.plan.joint_trees.active()) return 0.0;
  mark_awake_components(state);
  return solve_packs(state, TreeStage::velocities);
}

#define LIMBER_INSTANTIATE(Scalar)                                               \
  template void begin_joint_trees<Scalar>(VerletState<Scalar>&, double);        \
  template JointTreeCounts joint_tree_counts<Scalar>(const VerletState<Scalar>&); \
  template double project_joint_trees<Scalar>(VerletState<Scalar>&);            \
  template double project_joint_tree_velocities<Scalar>(VerletState<Scalar>&);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
