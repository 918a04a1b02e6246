#include "limber/kernel/relaxation/joint_trees.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <Eigen/Cholesky>

#include "limber/kernel/relaxation/joint_projection.hpp"
#include "limber/kernel/relaxation/tree_contacts.hpp"

namespace limber {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;
constexpr int kSide = JointTrees::kLimbParticles;

Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

// Where each tree joint's parts came from, to mark them held once the tree is known.
struct JointSources {
  std::int32_t constraint = -1, point_row = -1, align_row = -1;
  std::array<std::int32_t, 2> limit_row{-1, -1};
};

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

// The limb each particle belongs to (−1: none, or more than one: shared), and per limb whether
// it can move as a rigid cluster (every particle its own and movable).
template <typename Scalar>
std::vector<std::int32_t> limb_of_particles(const VerletState<Scalar>& state, JointTrees& trees, std::vector<bool>& rigid) {
  const std::uint32_t null_particle = state.particles.null_particle();
  const std::size_t limb_count = state.limbs.head.size();
  std::vector<std::int32_t> limb_of(state.particles.size(), -1);
  trees.limb_particles.assign(limb_count, {});
  trees.limb_framed.assign(limb_count, 0);
  rigid.assign(limb_count, true);
  std::vector<std::int32_t> body_of_limb(limb_count, -1);
  for (std::size_t b = 0; b < state.body_limb.size(); ++b) body_of_limb[state.body_limb[b]] = static_cast<std::int32_t>(b);
  const JointRowSet& rows = state.joint_rows;
  for (std::size_t l = 0; l < limb_count; ++l) {
    auto& particles = trees.limb_particles[l];
    particles.fill(null_particle);
    std::size_t n = 0;
    particles[n++] = state.limbs.head[l], particles[n++] = state.limbs.tail[l];
    const std::int32_t body = body_of_limb[l];
    if (body >= 0 && !rows.frame_plus.empty() && rows.frame_plus[static_cast<std::size_t>(body)] != null_particle) {
      particles[n++] = rows.frame_plus[static_cast<std::size_t>(body)], particles[n++] = rows.frame_minus[static_cast<std::size_t>(body)];
      trees.limb_framed[l] = 1;
    }
    if (state.limbs.centre[l] != kNoCentre) particles[n++] = state.limbs.centre[l];
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t p = particles[k];
      if (!(state.particles.inverse_mass[p] > 0)) rigid[l] = false;
      if (limb_of[p] >= 0) rigid[l] = rigid[static_cast<std::size_t>(limb_of[p])] = false;
      limb_of[p] = static_cast<std::int32_t>(l);
    }
  }
  return limb_of;
}

// The side of a joint a particle names: its limb, −1 for a pin (the world), or −2 for a particle
// a rigid limb does not own (the joint stays rows).
std::int32_t side_of(const std::vector<std::int32_t>& limb_of, const std::vector<bool>& rigid, bool movable, std::uint32_t p) {
  const std::int32_t limb = limb_of[p];
  if (limb < 0) return movable ? -2 : -1;
  return rigid[static_cast<std::size_t>(limb)] ? limb : -2;
}

// A limb's pose from its particles x[0..n) (head, tail, then F⁺ F⁻ if framed): its centre of
// mass and its frame (v, w, u); a stick's is the identity but for u in the third column.
struct LimbPose {
  Eigen::Vector3d centre;
  Eigen::Matrix3d frame;
};
LimbPose limb_pose(const Eigen::Vector3d* x, const double* mass, int n, bool framed) {
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  double total = 0;
  for (int k = 0; k < n; ++k) moment += mass[k] * x[k], total += mass[k];
  Eigen::Vector3d u = x[0] - x[1];
  u = u.norm() > 0 ? Eigen::Vector3d(u.normalized()) : Eigen::Vector3d::UnitZ();
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  frame.col(2) = u;
  if (framed) {
    Eigen::Vector3d v = x[2] - x[3];
    v -= v.dot(u) * u;
    v = v.norm() > 0 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX();
    frame.col(0) = v, frame.col(1) = u.cross(v);
  }
  return {moment / total, frame};
}

// A limb's particles' positions and masses; returns their count.
template <typename Scalar>
int limb_particles(const VerletState<Scalar>& state, const JointTrees& trees, std::size_t limb, Eigen::Vector3d* x, double* mass) {
  const auto& particles = trees.limb_particles[limb];
  int n = 0;
  for (; n < kSide && particles[n] != state.particles.null_particle(); ++n) {
    x[n] = state.particles.position(particles[n]).template cast<double>();
    mass[n] = 1.0 / static_cast<double>(state.particles.inverse_mass[particles[n]]);
  }
  return n;
}

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

// Writes joint j's J blocks into the scratch (read only if its component is factored afresh),
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
    if (!active || row >= 6) continue;
    active_limits |= static_cast<std::uint8_t>(1u << k);
    if (at_upper) limit_upper |= static_cast<std::uint8_t>(1u << k);
    c[row] = violation;
    block_a.block<1, 3>(row, 3) = -axis.transpose(), block_b.block<1, 3>(row, 3) = axis.transpose();
    ++row;
  }
  trees.active_limits[j] = active_limits;
  trees.limit_upper[j] = limit_upper;
  trees.rows[j] = static_cast<std::uint8_t>(row);
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
    int row = joint.rows();
    std::uint8_t held = 0;
    for (std::size_t l = 0; l < joint.limit.size(); ++l) {
      if (!(trees.active_limits[j] & (1u << l))) continue;
      const double mu = trees.elimination.work(static_cast<std::size_t>(order[k]))(row++);
      const bool upper = trees.limit_upper[j] & (1u << l);
      if (upper ? mu > 0 : mu < 0) held |= static_cast<std::uint8_t>(1u << (2 * l + (upper ? 0 : 1)));
    }
    trees.limit_held[j] = held;
  }
}

// Loads one component's limbs and joints at the current positions and solves it: work(limb) =
// (Δp, Δφ) for the right-hand side −C (positions), or (Δv, Δω) for −J·(v, ω) with each limb's
// rigid velocity (velocities: v of its centre, ω = I⁻¹ Σ m r × v, kept in trees.rate). The
// factor is reused while the component's active set is the one it was factored with, within
// a substep (a chord iteration: the limbs turn little between sweeps); the velocity stage
// factors afresh. Every limb block is positive definite (positive masses; a stick's spin
// regularized), so the factor cannot fail.
template <typename Scalar>
void solve_component(VerletState<Scalar>& state, JointTrees& trees, std::uint32_t index, bool velocities) {
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
  bool refactor = velocities || !trees.factored[index];
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    const std::int32_t node = order[k];
    if (node < limbs) {
      trees.elimination.work(static_cast<std::size_t>(node)).setZero();
      continue;
    }
    const auto j = static_cast<std::size_t>(node - limbs);
    const Vector6 c = assemble_joint(state, trees, j, velocities);
    refactor = refactor || trees.active_limits[j] != trees.factored_limits[j];
    Vector6& rhs = trees.elimination.work(static_cast<std::size_t>(node));
    if (!velocities) {
      rhs = -c;
      continue;
    }
    const JointTrees::Joint& joint = trees.joints[j];
    rhs = -(trees.block_b[j] * trees.rate[static_cast<std::size_t>(joint.limb_b)]);
    if (joint.limb_a >= 0) rhs -= trees.block_a[j] * trees.rate[static_cast<std::size_t>(joint.limb_a)];
  }
  if (refactor) {
    for (std::uint32_t k = component.begin; k < component.end; ++k) {
      const std::int32_t node = order[k];
      Matrix6& block = trees.elimination.diagonal(static_cast<std::size_t>(node));
      block.setZero();
      if (node < limbs) {
        block.topLeftCorner<3, 3>() = trees.mass[node] * Eigen::Matrix3d::Identity();
        block.bottomRightCorner<3, 3>() = trees.inertia[node];
        continue;
      }
      const auto j = static_cast<std::size_t>(node - limbs);
      trees.elimination.set_rows(j, trees.rows[j]);
      trees.factored_limits[j] = trees.active_limits[j];
    }
    trees.elimination.factor(component.begin, component.end, [&](std::size_t j, std::int32_t limb) -> const Matrix6& {
      return trees.joints[j].limb_a == limb ? trees.block_a[j] : trees.block_b[j];
    });
    trees.mobility_current[index] = 0;
  }
  trees.factored[index] = velocities ? 0 : 1;  // the velocity stage's factor is not the positions'
  trees.elimination.solve(component.begin, component.end);
  if (!velocities) hold_pushing_limits(trees, component);
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

using JointPairs = std::map<std::tuple<std::int32_t, std::int32_t, std::uint32_t>, std::size_t>;

// The limits of the tree joints found (rigid: no drive, no friction), limb to limb, into
// trees.limits; `side(p)` is side_of a particle.
template <typename Scalar, typename Side>
void attach_limits(const VerletState<Scalar>& state, JointTrees& trees, Side&& side, const JointPairs& joint_of_pair,
                   std::vector<JointSources>& sources) {
  const JointRowSet& rows = state.joint_rows;
  const std::uint32_t null_particle = state.particles.null_particle();
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    const JointRow& row = rows.rows[r];
    const bool limit = row.kind == JointRowKind::swing || row.kind == JointRowKind::twist || row.kind == JointRowKind::hinge;
    if (row.joint < 0 || !limit || row.drive || row.friction != 0 || row.stiffness != 0 || row.damping != 0 || row.blend != 0) continue;
    if (row.side_a == JointSide::world) continue;
    const std::int32_t a = side(row.particle[0]), b = side(row.particle[kJointRowSideParticles]);
    const auto found = joint_of_pair.find(std::make_tuple(std::min(a, b), std::max(a, b), 0u));
    if (a < 0 || b < 0 || found == joint_of_pair.end()) continue;
    JointTrees::Joint& joint = trees.joints[found->second];
    const auto free = std::find(joint.limit.begin(), joint.limit.end(), -1);
    if (joint.limb_a != a || free == joint.limit.end()) continue;
    const std::size_t slot = trees.limits.push(static_cast<JointRowBatches<double>::Index>(null_particle));
    for (std::size_t k = 0; k < kJointRowDirections; ++k) trees.limits.direction[k][slot] = row.direction[k];
    trees.limits.lower[slot] = row.lower, trees.limits.upper[slot] = row.upper;
    trees.limit_kind.push_back(row.kind);
    *free = static_cast<std::int32_t>(slot);
    JointSources& source = sources[found->second];
    source.limit_row[static_cast<std::size_t>(free - joint.limit.begin())] = static_cast<std::int32_t>(r);
  }

}

// Orders the tree joints into trees (the loops left to the sweeps), marks what the trees hold,
// finds each island's components and the rest shapes of their limbs, and sizes the scratch.
template <typename Scalar>
void order_trees(const VerletState<Scalar>& state, JointTrees& trees, const std::vector<std::int32_t>& limb_of,
                 const std::vector<JointSources>& sources) {
  const JointRowSet& rows = state.joint_rows;
  const std::size_t limb_count = trees.limb_particles.size();
  std::vector<std::int32_t> inboard(trees.joints.size()), outboard(trees.joints.size());
  std::vector<std::uint8_t> joint_rows(trees.joints.size());
  for (std::size_t j = 0; j < trees.joints.size(); ++j) {
    inboard[j] = trees.joints[j].limb_a, outboard[j] = trees.joints[j].limb_b;
    joint_rows[j] = static_cast<std::uint8_t>(trees.joints[j].rows());  // limits join while reached
  }
  TreeOrdering ordering = order_tree(limb_count, inboard, outboard);
  std::vector<bool> in_tree(trees.joints.size(), true);
  for (const std::uint32_t loop : ordering.loop_constraints) in_tree[loop] = false;
  trees.tree_constraint.assign(state.constraints.size(), 0);
  trees.tree_row.assign(rows.rows.size(), 0);
  for (std::size_t j = 0; j < trees.joints.size(); ++j) {
    if (!in_tree[j]) continue;
    if (sources[j].constraint >= 0) trees.tree_constraint[static_cast<std::size_t>(sources[j].constraint)] = 1;
    if (sources[j].point_row >= 0) trees.tree_row[static_cast<std::size_t>(sources[j].point_row)] = 1;
    if (sources[j].align_row >= 0) trees.tree_row[static_cast<std::size_t>(sources[j].align_row)] = 1;
    for (const std::int32_t r : sources[j].limit_row) {
      if (r >= 0) trees.tree_row[static_cast<std::size_t>(r)] = 1;
    }
  }
  // Components of more than one limb, by island (a limb's island from the islands' limb ranges).
  std::vector<std::uint32_t> island_of_limb(limb_count, 0);
  for (std::size_t i = 0; i < state.islands.size(); ++i) {
    std::fill(island_of_limb.begin() + state.islands[i].limb_begin, island_of_limb.begin() + state.islands[i].limb_end,
              static_cast<std::uint32_t>(i));
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> island_components;
  for (std::size_t k = 0; k < ordering.components.size(); ++k) {
    const TreeOrdering::Component& component = ordering.components[k];
    if (component.end - component.begin < 2) continue;
    island_components.emplace_back(island_of_limb[static_cast<std::size_t>(component.body)], static_cast<std::uint32_t>(k));
  }
  trees.island_components = group_by_row(state.islands.size(), island_components);
  // The limbs of those components are rigid bodies: their rest shapes, and their own
  // constraints (link, centre, frame) held by the tree (load_limb) rather than the sweeps.
  std::vector<bool> tree_limb(limb_count, false);
  for (const auto& [island, k] : island_components) {
    const TreeOrdering::Component& component = ordering.components[k];
    for (std::uint32_t n = component.begin; n < component.end; ++n) {
      if (ordering.order[n] < static_cast<std::int32_t>(limb_count)) tree_limb[static_cast<std::size_t>(ordering.order[n])] = true;
    }
  }
  trees.rest_offset.assign(limb_count, {});
  for (std::size_t l = 0; l < limb_count; ++l) {
    Eigen::Vector3d x[kSide];
    double mass[kSide];
    const int n = limb_particles(state, trees, l, x, mass);
    const LimbPose pose = limb_pose(x, mass, n, trees.limb_framed[l]);
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d r = x[k] - pose.centre;
      trees.rest_offset[l][static_cast<std::size_t>(k)] =
          trees.limb_framed[l] ? Eigen::Vector3d(pose.frame.transpose() * r) : Eigen::Vector3d(0, 0, r.dot(pose.frame.col(2)));
    }
  }
  const auto own = [&](std::uint32_t p) { return limb_of[p] >= 0 && tree_limb[static_cast<std::size_t>(limb_of[p])]; };
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
    if (own(i) && limb_of[i] == limb_of[j]) trees.tree_constraint[c] = 1;
  }
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    const JointRow& row = rows.rows[r];
    if (row.joint < 0 && row.kind == JointRowKind::point && own(row.particle[0])) trees.tree_row[r] = 1;  // a frame's row
  }
  trees.limb_of_particle.assign(limb_of.size(), -1);
  for (std::size_t p = 0; p < limb_of.size(); ++p) {
    if (own(static_cast<std::uint32_t>(p))) trees.limb_of_particle[p] = limb_of[p];
  }
  trees.component_of_limb.assign(limb_count, -1);
  trees.component_island.assign(ordering.components.size(), 0);
  for (const auto& [island, k] : island_components) {
    trees.component_island[k] = island;
    const TreeOrdering::Component& component = ordering.components[k];
    for (std::uint32_t n = component.begin; n < component.end; ++n) {
      const std::int32_t node = ordering.order[n];
      if (node < static_cast<std::int32_t>(limb_count)) trees.component_of_limb[static_cast<std::size_t>(node)] = static_cast<std::int32_t>(k);
    }
  }
  trees.elimination.assign(std::move(ordering), limb_count, std::move(joint_rows));
  trees.centre.assign(limb_count, Eigen::Vector3d::Zero());
  trees.frame.assign(limb_count, Eigen::Matrix3d::Identity());
  trees.block_a.assign(trees.joints.size(), Matrix6::Zero());
  trees.block_b.assign(trees.joints.size(), Matrix6::Zero());
  trees.rate.assign(limb_count, Vector6::Zero());
  trees.mass.assign(limb_count, 0.0);
  trees.inertia.assign(limb_count, Eigen::Matrix3d::Zero());
  trees.active_limits.assign(trees.joints.size(), 0);
  trees.limit_upper.assign(trees.joints.size(), 0);
  trees.limit_held.assign(trees.joints.size(), 0);
  trees.factored_limits.assign(trees.joints.size(), 0);
  trees.rows.assign(trees.joints.size(), 0);
  trees.factored.assign(trees.elimination.ordering().components.size(), 0);
  trees.solves.assign(trees.factored.size(), 0);
  trees.newton_steps.assign(trees.factored.size(), 0);
  trees.capped.assign(trees.factored.size(), 0);
  trees.mobility_current.assign(trees.factored.size(), 0);
  trees.load_scale.assign(trees.factored.size(), 1.0);
  trees.settled.assign(trees.factored.size(), 0);
  trees.joint_motion.assign(limb_count, Vector6::Zero());
}

}  // namespace

template <typename Scalar>
void prepare_joint_trees(VerletState<Scalar>& state) {
  JointTrees& trees = state.plan.joint_trees;
  JointTrees empty;  // (g++ 12 fails on `trees = JointTrees{}`: an internal compiler error)
  trees = std::move(empty);
  const VerletOptions& options = state.options;
  if (options.joint_solve != JointSolve::tree) return;
  const auto refuse = [](const char* what) { throw std::invalid_argument(std::string("options: joint_solve tree needs ") + what); };
  if (options.rule != RelaxationRule::weighted) refuse("the weighted rule (limbs keep their masses)");
  if (options.solver != RelaxationSolver::gauss_seidel || options.order != SweepOrder::coloured) {
    refuse("the coloured Gauss-Seidel sweep (not Jacobi, the sequential sweep or the direct solver)");
  }
  if (options.layout == ParticleLayout::aos || options.layout == ParticleLayout::aosoa) refuse("the SoA layout");

  std::vector<bool> rigid;
  const std::vector<std::int32_t> limb_of = limb_of_particles(state, trees, rigid);
  const auto movable = [&](std::uint32_t p) { return state.particles.inverse_mass[p] > 0; };
  const auto side = [&](std::uint32_t p) { return side_of(limb_of, rigid, movable(p), p); };
  // One tree joint per pair of limbs (or limb and world pin): its point part and its hinge axis.
  std::vector<JointSources> sources;
  JointPairs joint_of_pair;
  const std::uint32_t null_particle = state.particles.null_particle();
  const auto joint_for = [&](std::int32_t a, std::int32_t b, std::uint32_t pin, bool point) -> JointTrees::Joint* {
    if (a == -2 || b == -2 || a == b || b < 0) return nullptr;
    const auto key = std::make_tuple(std::min(a, b), std::max(a, b), a < 0 ? pin : 0u);
    auto found = joint_of_pair.find(key);
    if (found == joint_of_pair.end() || (point ? trees.joints[found->second].point : trees.joints[found->second].align_row >= 0)) {
      // A second part of one kind between one pair closes a loop: its own node, which order_tree reports.
      found = joint_of_pair.insert_or_assign(key, trees.joints.size()).first;
      JointTrees::Joint joint;
      joint.limb_a = a, joint.limb_b = b;
      joint.particle.fill(null_particle);
      trees.joints.push_back(joint);
      sources.emplace_back();
    }
    return &trees.joints[found->second];
  };
  for (const auto& [c, reference] : state.joint_constraints) {
    const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
    std::int32_t a = side(i), b = side(j);
    std::uint32_t p_a = i, p_b = j;
    if (b == -1) std::swap(a, b), std::swap(p_a, p_b);  // the world is side A
    JointTrees::Joint* joint = joint_for(a, b, p_a, true);
    if (joint == nullptr) continue;
    const bool a_first = joint->limb_a == a;
    joint->point = true;
    joint->particle[0] = a_first ? p_a : p_b, joint->coefficient[0] = -1;
    joint->particle[kSide] = a_first ? p_b : p_a, joint->coefficient[kSide] = 1;
    sources[static_cast<std::size_t>(joint - trees.joints.data())].constraint = static_cast<std::int32_t>(c);
  }
  const JointRowSet& rows = state.joint_rows;
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    const JointRow& row = rows.rows[r];
    if (row.joint < 0) continue;  // a frame's own row
    const bool rigid_equality = row.lower == 0 && row.upper == 0 && row.stiffness == 0 && row.damping == 0 && row.friction == 0 && !row.drive;
    if (row.kind == JointRowKind::point) {
      const std::int32_t a = side(row.particle[0]), b = side(row.particle[kJointRowSideParticles]);
      JointTrees::Joint* joint = joint_for(a, b, row.particle[0], true);
      if (joint == nullptr) continue;
      const bool a_first = joint->limb_a == a;
      joint->point = true;
      for (int s = 0; s < 2; ++s) {
        const std::size_t from = static_cast<std::size_t>((s == 0) == a_first ? 0 : kJointRowSideParticles);
        for (int k = 0, n = 0; k < 4; ++k) {
          const std::uint32_t p = row.particle[from + k];
          if (p == null_particle || row.direction[from + k] == 0) continue;
          joint->particle[s * kSide + n] = p, joint->coefficient[s * kSide + n] = row.direction[from + k], ++n;
        }
      }
      sources[static_cast<std::size_t>(joint - trees.joints.data())].point_row = static_cast<std::int32_t>(r);
    } else if (row.kind == JointRowKind::align && rigid_equality) {
      const std::int32_t a = row.side_a == JointSide::world ? -1 : side(row.particle[0]);
      const std::int32_t b = side(row.particle[kJointRowSideParticles]);
      if (b < 0 || (a >= 0 && !trees.limb_framed[a]) || !trees.limb_framed[b]) continue;
      JointTrees::Joint* joint = joint_for(a, b, null_particle, false);
      if (joint == nullptr || joint->limb_a != a) continue;  // a tree keeps A inboard
      const Eigen::Vector3d d(row.direction[0], row.direction[1], row.direction[2]);
      const Eigen::Vector3d helper = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      joint->align_row = static_cast<std::int32_t>(r);
      joint->t1 = d.cross(helper).normalized(), joint->t2 = d.normalized().cross(joint->t1);
      joint->e = Eigen::Vector3d(row.direction[3], row.direction[4], row.direction[5]).normalized();
      sources[static_cast<std::size_t>(joint - trees.joints.data())].align_row = static_cast<std::int32_t>(r);
    }
  }
  attach_limits(state, trees, side, joint_of_pair, sources);
  order_trees(state, trees, limb_of, sources);
  if (trees.island_components.entries.empty()) trees.joints.clear();  // nothing to solve: inactive
  // The rattle rule's contacts are inequalities of its velocity stage too: they stay rows there.
  trees.with_contacts = trees.active() && !uses_rattle(state);
}

// Newton steps a tree takes in one call at most, and the largest move after which it takes
// another, from a fresh factor: a Newton move δ on a lever r leaves about δ²/r (1e-5 m on
// 0.1 m: 1e-9 m). The first step of a call reuses the substep's factor (a chord step).
constexpr int kNewtonSteps = 4;
constexpr double kNewtonMove = 1e-5;

template <typename Scalar>
void begin_joint_trees(VerletState<Scalar>& state, double dt) {
  JointTrees& trees = state.plan.joint_trees;
  std::fill(trees.factored.begin(), trees.factored.end(), std::uint8_t{0});
  gather_tree_contacts(state, dt);
  for (auto* counts : {&trees.solves, &trees.newton_steps, &trees.capped}) std::fill(counts->begin(), counts->end(), 0u);
}

template <typename Scalar>
JointTreeCounts joint_tree_counts(const VerletState<Scalar>& state) {
  const JointTrees& trees = state.plan.joint_trees;
  JointTreeCounts counts;
  for (std::size_t k = 0; k < trees.solves.size(); ++k) {
    counts.solves += trees.solves[k], counts.newton_steps += trees.newton_steps[k], counts.capped += trees.capped[k];
  }
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

// Newton steps `first`… of one component's tree on the positions, each solved and moved (the
// first a chord step while the substep's factor serves); returns the largest move, m (`largest`
// so far included).
template <typename Scalar>
double newton_steps(VerletState<Scalar>& state, std::uint32_t index, int first, double largest) {
  JointTrees& trees = state.plan.joint_trees;
  for (int newton = first; newton < kNewtonSteps; ++newton) {
    if (newton > 0) trees.factored[index] = 0;
    solve_component(state, trees, index, false);
    ++trees.newton_steps[index];
    const double moved = move_component(state, index);
    largest = std::max(largest, moved);
    if (moved < kNewtonMove) return largest;
  }
  ++trees.capped[index];
  return largest;
}

// Forgets the limits held in component `index`'s last call (hold_pushing_limits).
void release_limits(JointTrees& trees, std::uint32_t index) {
  const TreeOrdering::Component& component = trees.elimination.ordering().components[index];
  const auto& order = trees.elimination.ordering().order;
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    if (order[k] >= trees.elimination.body_count()) trees.limit_held[static_cast<std::size_t>(order[k] - trees.elimination.body_count())] = 0;
  }
}

// One component's tree on the positions, without contacts; returns the largest move, m.
template <typename Scalar>
double solve_positions(VerletState<Scalar>& state, std::uint32_t index) {
  ++state.plan.joint_trees.solves[index];
  release_limits(state.plan.joint_trees, index);
  return newton_steps(state, index, 0, 0.0);
}

// A round of a component with contacts (tree_contacts.hpp), stage 1: a Newton step of its joints
// (the first round's a chord step while the substep's factor serves), solved but not applied
// (JointTrees::joint_motion), and its tree's inverse diagonal. A component without contacts is
// solved whole in the first round.
template <typename Scalar>
double contact_round_joints(VerletState<Scalar>& state, std::uint32_t index, int round) {
  JointTrees& trees = state.plan.joint_trees;
  if (trees.component_contacts.row(index).empty()) return round == 0 ? solve_positions(state, index) : 0.0;
  if (trees.settled[index]) return 0;
  if (round == 0) ++trees.solves[index], release_limits(trees, index);
  if (round > 0) trees.factored[index] = 0;
  solve_component(state, trees, index, false);
  ++trees.newton_steps[index];
  const TreeOrdering::Component& component = trees.elimination.ordering().components[index];
  if (!trees.mobility_current[index]) trees.elimination.inverse_diagonal(component.begin, component.end);
  trees.mobility_current[index] = 1;
  for_each_limb(trees, component, [&](std::size_t limb) { trees.joint_motion[limb] = trees.elimination.work(limb); });
  return 0;
}

// Stage 3 of a round: the component's contacts' loads solved with the same factor, their motion
// scaled so that no contact overshoots, added to the joints' step and applied. The component is
// settled when that moves no particle by kNewtonMove.
template <typename Scalar>
double contact_round_finish(VerletState<Scalar>& state, std::uint32_t index, int round) {
  JointTrees& trees = state.plan.joint_trees;
  if (trees.component_contacts.row(index).empty() || trees.settled[index]) return 0;
  const TreeOrdering::Component& component = trees.elimination.ordering().components[index];
  for (std::uint32_t k = component.begin; k < component.end; ++k) trees.elimination.work(static_cast<std::size_t>(trees.elimination.ordering().order[k])).setZero();
  const bool loads = add_tree_contact_loads(trees, index);
  double scale = 1;
  if (loads) {
    trees.elimination.solve(component.begin, component.end);
    scale = tree_contact_overshoot(trees, index);
  }
  trees.load_scale[index] = scale;
  for_each_limb(trees, component, [&](std::size_t limb) {
    Vector6& motion = trees.elimination.work(limb);
    motion = loads ? Vector6(trees.joint_motion[limb] + motion / scale) : trees.joint_motion[limb];
  });
  const double moved = move_component(state, index);
  trees.settled[index] = moved < kNewtonMove ? 1 : 0;
  if (!trees.settled[index] && round == kNewtonSteps - 1) ++trees.capped[index];
  return moved;
}

// After the rounds, a component they left unsettled takes one more Newton step of its joints
// alone, so that every sweep still ends with the joints closed (its contacts' next sweep's).
template <typename Scalar>
double close_joints(VerletState<Scalar>& state, std::uint32_t index) {
  JointTrees& trees = state.plan.joint_trees;
  if (trees.component_contacts.row(index).empty() || trees.settled[index]) return 0;
  trees.factored[index] = 0;
  solve_component(state, trees, index, false);
  ++trees.newton_steps[index];
  return move_component(state, index);
}

// One component's tree on the velocities; returns the largest |Δv|, m/s.
template <typename Scalar>
double solve_velocities(VerletState<Scalar>& state, std::uint32_t index) {
  JointTrees& trees = state.plan.joint_trees;
  const std::uint32_t null_particle = state.particles.null_particle();
  solve_component(state, trees, index, true);
  double largest = 0;
  for_each_limb(trees, trees.elimination.ordering().components[index], [&](std::size_t limb) {
    const Vector6& change = trees.elimination.work(limb);
    for (const std::uint32_t p : trees.limb_particles[limb]) {
      if (p == null_particle) break;
      const Eigen::Vector3d r = state.particles.position(p).template cast<double>() - trees.centre[limb];
      const Eigen::Vector3d dv = change.head<3>() + change.tail<3>().cross(r);
      largest = std::max(largest, dv.norm());
      state.particles.set_velocity(p, (state.particles.velocity(p).template cast<double>() + dv).template cast<Scalar>());
    }
  });
  return largest;
}

// The awake islands' trees as tasks, one an island, on the relaxation's threads: islands share
// no limb, particle, joint or elimination node, so any split gives the same bits.
enum class TreeStage { positions, contact_joints, contact_finish, close_joints, velocities };

template <typename Scalar>
struct IslandStage {
  VerletState<Scalar>* state;
  TreeStage kind;
  int round = 0;
  static double run(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const IslandStage*>(context);
    VerletState<Scalar>& state = *stage.state;
    double largest = 0;
    for (const std::uint32_t index : state.plan.joint_trees.island_components.row(state.awake_islands[task])) {
      switch (stage.kind) {
        case TreeStage::positions: largest = std::max(largest, solve_positions(state, index)); break;
        case TreeStage::contact_joints: largest = std::max(largest, contact_round_joints(state, index, stage.round)); break;
        case TreeStage::contact_finish: largest = std::max(largest, contact_round_finish(state, index, stage.round)); break;
        case TreeStage::close_joints: largest = std::max(largest, close_joints(state, index)); break;
        case TreeStage::velocities: largest = std::max(largest, solve_velocities(state, index)); break;
      }
    }
    return largest;
  }
};

template <typename Scalar>
double solve_awake_islands(VerletState<Scalar>& state, TreeStage kind, int round = 0) {
  const IslandStage<Scalar> stage{&state, kind, round};
  const std::size_t count = state.awake_islands.size();
  if (joint_trees_on_threads(state.plan) && count > 1) return state.plan.runner->run(count, &IslandStage<Scalar>::run, &stage);
  double largest = 0;
  for (std::size_t task = 0; task < count; ++task) largest = std::max(largest, IslandStage<Scalar>::run(&stage, task));
  return largest;
}

}  // namespace

template <typename Scalar>
double project_joint_trees(VerletState<Scalar>& state) {
  JointTrees& trees = state.plan.joint_trees;
  if (!trees.active()) return 0.0;
  if (trees.contacts.empty()) return solve_awake_islands(state, TreeStage::positions);
  // Rounds of the stages of tree_contacts.hpp (contacts between islands read both sides' steps),
  // each a Newton step of every component not yet settled, its contacts with it.
  std::fill(trees.settled.begin(), trees.settled.end(), std::uint8_t{0});
  double largest = 0;
  for (int round = 0; round < kNewtonSteps; ++round) {
    largest = std::max(largest, solve_awake_islands(state, TreeStage::contact_joints, round));
    tree_contact_impulses(state);
    largest = std::max(largest, solve_awake_islands(state, TreeStage::contact_finish, round));
    accumulate_tree_contact_impulses(trees);
    bool settled = true;
    for (const std::uint32_t island : state.awake_islands) {
      for (const std::uint32_t index : trees.island_components.row(island)) {
        settled = settled && (trees.settled[index] || trees.component_contacts.row(index).empty());
      }
    }
    if (settled) return largest;
  }
  return std::max(largest, solve_awake_islands(state, TreeStage::close_joints));
}

template <typename Scalar>
double project_joint_tree_velocities(VerletState<Scalar>& state) {
  return state.plan.joint_trees.active() ? solve_awake_islands(state, TreeStage::velocities) : 0.0;
}

#define LIMBER_INSTANTIATE(Scalar)                                               \
  template void prepare_joint_trees<Scalar>(VerletState<Scalar>&);              \
  template void begin_joint_trees<Scalar>(VerletState<Scalar>&, double);        \
  template JointTreeCounts joint_tree_counts<Scalar>(const VerletState<Scalar>&); \
  template double project_joint_trees<Scalar>(VerletState<Scalar>&);            \
  template double project_joint_tree_velocities<Scalar>(VerletState<Scalar>&);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
