// What relaxation needs besides the particles. A coloured sweep: the awake constraints in colour
// batches, Jacobi's accumulators, the interleaved particle copy for the AoS/AoSoA layouts, and
// the threads (rebuilt, not re-coloured, when islands sleep or wake). The direct solver: its
// elimination tree and multipliers (DirectProjection).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "limber/kernel/numerics/constraint_elimination.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"
#include "limber/kernel/particles/joint_rows.hpp"
#include "limber/kernel/threading/block_runner.hpp"
#include "limber/layouts/aligned_array.hpp"
#include "limber/layouts/constraints/constraint_batches.hpp"
#include "limber/layouts/constraints/contact_row_batches.hpp"
#include "limber/layouts/constraints/joint_row_batches.hpp"
#include "limber/layouts/graph/compressed_rows.hpp"
#include "limber/layouts/particles/interleaved_particles.hpp"

namespace limber {

/// A counter that threads add to (relaxed: only the total is read, after the stage) and that a
/// copied state copies.
struct SharedCounter {
  std::atomic<std::uint64_t> value{0};
  SharedCounter() = default;
  SharedCounter(const SharedCounter& other) : value(other.value.load()) {}
  SharedCounter& operator=(const SharedCounter& other) {
    value.store(other.value.load());
    return *this;
  }
};

/// The direct solver's structure and multipliers (kernel/relaxation/direct_projection.hpp).
/// Built at compile; nothing is allocated while stepping.
template <typename Scalar>
struct DirectProjection {
  /// Bodies of the elimination are the movable particles (pinned ones are the world); its
  /// constraints are state.constraints, same indices. Distance constraints have one row,
  /// zero-length joints three.
  TreeElimination<Scalar, 3> elimination;
  /// The same components in constraint space (constraint_elimination.hpp), for those whose
  /// particles carry at most kMaxFrontRows rows each (in_constraint_space, per component); the
  /// rest use `elimination`. Each constraint's direction (one-row constraints) and compliance
  /// its last factor used (a compliance of NaN: none yet): a factor is
  /// kept while they stay the same bits — through a rattle substep's Newton steps, and from the
  /// velocity stage into the next substep, whose start gradients are the same positions'.
  ConstraintElimination<Scalar> constraint_space;
  std::vector<std::uint8_t> in_constraint_space;
  std::vector<Eigen::Matrix<Scalar, 3, 1>> factored_direction;
  std::vector<Scalar> factored_compliance;
  std::vector<Eigen::Matrix<Scalar, 3, 1>> correction;  ///< per body: Δ of the last solve (scratch)
  std::vector<std::int32_t> body_of_particle;     ///< −1 for a pinned particle
  std::vector<std::uint32_t> particle_of_body;
  std::vector<Scalar> body_mass;  ///< 1/w (weighted rule) or 1 (unweighted), kg
  /// Per island: its components (indices into elimination.ordering().components), and its
  /// loop-closing constraints, which Gauss-Seidel projects after each Newton step.
  CompressedRows<std::uint32_t> island_components, island_loop_constraints;
  /// Per constraint: its accumulated multiplier this step (Δλ summed; kg·m, a position-level
  /// impulse; rows as above), the unit direction n of a distance constraint at the current
  /// linearization, and its compliance α̃ = α/Δt² (m/N over s², i.e. 1/kg).
  std::vector<Eigen::Matrix<Scalar, 3, 1>> multiplier, direction;
  std::vector<Scalar> scaled_compliance;
  double multiplier_time_step = 0;  ///< Δt the multipliers were computed with (warm start rescales by (Δt/this)²)
};

/// A contact of a tree limb, solved with the joint trees (kernel/relaxation/tree_contacts.hpp):
/// a contact row (kernel/particles/contact_rows.hpp) whose moving sides are all tree limbs, or a
/// plane contact of a tree limb's feature. Found each substep; the sweeps leave it alone.
struct TreeContact {
  enum class Source : std::uint8_t { row, plane };
  Source source = Source::row;
  std::uint32_t index = 0;                   ///< its ContactRow or PlaneContact
  std::array<std::int32_t, 2> limb{-1, -1};  ///< the tree limb of each side; −1: static, or asleep
  bool loop = false;  ///< both sides are limbs of one tree (a limb against its own body)
  double friction = 0;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  ///< its point Σ c_k x_k at the substep's start, m
  /// Accumulated over the substep's sweeps: the normal push λ (kg·m, ≥ 0) and the tangential
  /// friction impulse (kg·m, |·| ≤ μλ), as the contact rows' batches keep them.
  double lambda = 0;
  Eigen::Vector3d tangent = Eigen::Vector3d::Zero();
  /// What the current round's iterations have taken so far (kg·m), added to the above when it ends.
  double round_push = 0;
  Eigen::Vector3d round_slide = Eigen::Vector3d::Zero();
  // A round's (scratch). At the round's start: the normal, separation C (m) and slip since the
  // substep began (m), each side's normal row J (1 × 6) and point map P (3 × 6) on its limb.
  // The impulses asked (kg·m) before the components' scaling, whether each side acts (its
  // component not settled), and each side's load (6: force | torque) with the motion of its
  // point it asked for, along n (m).
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(), slip = Eigen::Vector3d::Zero();
  double separation = 0;
  std::array<Eigen::Matrix<double, 6, 1>, 2> normal_jacobian{};
  std::array<Eigen::Matrix<double, 3, 6>, 2> point_jacobian{};
  /// Each acting side's mobility along n (J Z Jᵀ, 1/kg) and at its point (P Z Pᵀ), the round's.
  /// A loop's along n is exact, its sides' coupling included (take_loop_mobilities): loop_mobility.
  std::array<double, 2> normal_mobility{}, loop_mobility{};
  std::array<Eigen::Matrix3d, 2> point_mobility{};
  double push = 0;
  Eigen::Vector3d slide = Eigen::Vector3d::Zero();
  std::array<bool, 2> acting{};
  std::array<Eigen::Matrix<double, 6, 1>, 2> load{};
  std::array<double, 2> wanted{};
  std::array<Eigen::Vector3d, 2> wanted_slide{};  ///< the tangential motion of the side's point asked for, m
};

/// Thread time of the joint trees' stages since the substep began, s, when the step is profiled
/// (StepProfile's tree_* times; 0 otherwise), positions and velocities alike: staging (the limbs'
/// loads, the joints' assembly with their limits' measures, the limits held), elimination (a
/// pack's gathers, factor, solves, path solves and scatters), moves (the limbs' rigid moves and
/// the velocity stage's changes) and contacts (their gathering, impulses, loads and overshoot).
struct TreeStageSeconds {
  double staging = 0, elimination = 0, moves = 0, contacts = 0;

  TreeStageSeconds& operator+=(const TreeStageSeconds& part) {
    staging += part.staging, elimination += part.elimination, moves += part.moves, contacts += part.contacts;
    return *this;
  }
};

/// What the joint trees did since the substep began (StepProfile's tree counts), per component
/// or summed: position solves (project_joint_trees calls), their Newton steps, the solves that
/// stopped at the cap with a move still ≥ 1e-5 m; and the elimination's work, positions and
/// velocities alike: factors, inverse diagonals (the contacts' mobilities), whole
/// back-substitutions, and path solves (a loop's mobility, along two paths to the root); summed
/// only, the lanes the factors ran in (a pack's factor counts all its lanes, used or not) and the
/// stages' times.
struct JointTreeCounts {
  int solves = 0, newton_steps = 0, capped = 0;
  int factors = 0, inverse_diagonals = 0, substitutions = 0, path_solves = 0, lane_slots = 0;
  TreeStageSeconds seconds;

  JointTreeCounts& operator+=(const JointTreeCounts& part) {
    solves += part.solves, newton_steps += part.newton_steps, capped += part.capped;
    factors += part.factors, inverse_diagonals += part.inverse_diagonals;
    substitutions += part.substitutions, path_solves += part.path_solves, lane_slots += part.lane_slots;
    seconds += part.seconds;
    return *this;
  }
};

struct TreePacks;  // kernel/relaxation/tree_packs.hpp

/// Owns the joint trees' SIMD packs; copying a state gives the copy its own (they are scratch
/// a solve writes).
class TreePacksHandle {
 public:
  TreePacksHandle();
  ~TreePacksHandle();
  TreePacksHandle(const TreePacksHandle& other);
  TreePacksHandle& operator=(const TreePacksHandle& other);
  TreePacksHandle(TreePacksHandle&&) noexcept;
  TreePacksHandle& operator=(TreePacksHandle&&) noexcept;
  TreePacks& operator*() const { return *packs_; }
  TreePacks* operator->() const { return packs_.get(); }

 private:
  std::unique_ptr<TreePacks> packs_;
};

/// The exact joint-tree solve's structure (kernel/relaxation/joint_trees.hpp), built at compile;
/// its per-solve arrays are scratch sized there, so nothing is allocated while stepping.
struct JointTrees {
  /// Most particles of one limb (head, tail, F⁺, F⁻, centre) and of one side of a point joint.
  static constexpr int kLimbParticles = 5;
  /// Bodies are state.limbs (rigid clusters of their particles: Δp, Δφ about the centre of
  /// mass); constraints are the tree joints, one per pair of joined limbs (or limb and world).
  TreeElimination<double, 6> elimination;
  std::vector<std::array<std::uint32_t, kLimbParticles>> limb_particles;  ///< the null particle past the last
  std::vector<std::uint8_t> limb_framed;  ///< carries F⁺, F⁻ (else a stick: on-axis particles only)
  /// Per limb particle: its place in the limb's rest shape, in the limb's frame (v, w, u)
  /// about its centre of mass (a stick: (0, 0, z) along u), m.
  std::vector<std::array<Eigen::Vector3d, kLimbParticles>> rest_offset;
  /// A tree joint: its limbs (−1: the world), its point constraint C = Σ c_k x_k over up to
  /// 2·kLimbParticles particles (a world pin is a particle of inverse mass 0; no point part: the
  /// null particle), and its hinge axis (align rows: −1 if none): t₁, t₂ ⟂ the axis in A's
  /// frame (v, w, u) coordinates, e the axis in B's, C = (t₁·e, t₂·e).
  struct Joint {
    std::int32_t limb_a = -1, limb_b = -1;
    std::array<std::uint32_t, 2 * kLimbParticles> particle{};
    std::array<double, 2 * kLimbParticles> coefficient{};
    bool point = false;
    std::int32_t align_row = -1;
    Eigen::Vector3d t1 = Eigen::Vector3d::Zero(), t2 = Eigen::Vector3d::Zero(), e = Eigen::Vector3d::Zero();
    /// Its limits (swing, twist, hinge range): slots of `limits` (−1: none), each a row of the
    /// joint's at limit_row(k) whether reached or not (decoupled while idle: fixed_rows).
    std::array<std::int32_t, 2> limit{-1, -1};
    /// The point's and axis' rows.
    int rows() const { return (point ? 3 : 0) + (align_row >= 0 ? 2 : 0); }
    /// The row of limit k (after rows() and the limits before it), or −1 when k has no slot or
    /// no row is left for it (a joint has 6 at most).
    int limit_row(std::size_t k) const {
      if (limit[k] < 0) return -1;
      const int row = rows() + (k == 1 && limit[0] >= 0 ? 1 : 0);
      return row < 6 ? row : -1;
    }
    /// Every row the joint can hold: its point and axis rows and a row per limit, reached or
    /// not. The row count is fixed so that a component's elimination has one shape whatever
    /// its active set (an idle limit's row is decoupled: J = 0, −A = −1, right-hand side 0, so
    /// its μ is 0), which lets components of one skeleton share SIMD lanes.
    int fixed_rows() const {
      int count = rows();
      for (std::size_t k = 0; k < limit.size(); ++k) count += limit_row(k) >= 0 ? 1 : 0;
      return count;
    }
  };
  std::vector<Joint> joints;
  /// The tree joints' limit rows, one slot each (their directions and bounds, as the sweeps hold
  /// them: joint_projection::measure reads them).
  JointRowBatches<double> limits;
  std::vector<JointRowKind> limit_kind;
  /// What the sweeps leave to the tree: per distance constraint and per joint row, 1 if a tree
  /// joint holds it (the loops' and the rows' of islands that cannot be solved stay 0).
  std::vector<std::uint8_t> tree_constraint, tree_row;
  /// Per island: its components (indices into elimination.ordering().components).
  CompressedRows<std::uint32_t> island_components;
  /// Scratch per solve. Per limb: its centre of mass (m), frame (v, w, u columns), mass (kg),
  /// inertia about the centre (kg·m²; a stick's regularized) and rigid velocity (v of the
  /// centre, m/s; ω, rad/s) and mobility (its block of the constrained system's inverse,
  /// TreeElimination::inverse_diagonal). Per joint: its J blocks on A and B (rows × 6: [linear |
  /// angular]) and its active limits (bit k: limit k).
  std::vector<Eigen::Vector3d> centre;
  std::vector<Eigen::Matrix3d> frame;
  std::vector<double> mass;
  std::vector<Eigen::Matrix3d> inertia;
  std::vector<Eigen::Matrix<double, 6, 1>> rate;
  std::vector<Eigen::Matrix<double, 6, 6>> mobility, block_a, block_b;
  std::vector<std::uint8_t> active_limits;
  /// Per joint: its active limits at their upper bound (bit k), and those a call holds at its
  /// next Newton step (bit 2k: at the upper bound, 2k + 1: at the lower; hold_pushing_limits).
  std::vector<std::uint8_t> limit_upper, limit_held;
  /// Counts since the substep began (begin_joint_trees), per component, for the step's profile
  /// (each written by its pack's task only).
  std::vector<JointTreeCounts> counts;
  /// The contacts' time outside the packs' tasks since the substep began, s (profiled steps only).
  double contact_seconds = 0;
  /// Contacts solved with the trees (tree_contacts.hpp; the pbd rule only): per particle, the
  /// tree limb it belongs to (−1: none); per limb its component (−1: none); per component its
  /// island. Per substep: the contacts, and by component the ones it has a side in.
  std::vector<std::int32_t> limb_of_particle, component_of_limb;
  std::vector<std::uint32_t> component_island;
  bool with_contacts = false;
  std::vector<TreeContact> contacts;
  CompressedRows<std::uint32_t> component_contacts;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> contact_pairs;  ///< scratch for component_contacts
  double recovery = 0;  ///< the substep's push-out allowance for an overlap it began with, m
  /// Per limb: the joints' motion of a sweep's first Newton step (Δp, Δφ), before the contacts'
  /// loads are added to it. Per component: settled this sweep (its round moved it little), and
  /// the factor by which the contacts' motion was scaled down this sweep (≥ 1).
  std::vector<Eigen::Matrix<double, 6, 1>> joint_motion;
  std::vector<Eigen::Matrix<double, 6, 1>> load_motion;  ///< per limb: the contacts' motion so far this round
  std::vector<std::uint8_t> settled;
  /// Per elimination node (a component's slice its own): the paths a loop's response runs on.
  std::vector<std::int32_t> path_scratch;
  std::vector<double> load_scale;
  /// The components grouped by shape into packs solved side by side in SIMD lanes
  /// (tree_packs.hpp), and per component whether its island is awake (refreshed each call).
  TreePacksHandle packs;
  std::vector<std::uint8_t> component_awake;
  bool active() const { return !joints.empty(); }
};

template <typename Scalar>
struct RelaxationPlan {
  ConstraintBatches<Scalar> batches;
  /// Jacobi: per particle, the sum of this sweep's corrections (m) and 1/(number of constraints
  /// on it), 0 for a particle no constraint moves.
  AlignedArray<Scalar> sum_x, sum_y, sum_z, inverse_count;
  /// The particles in the AoS or AoSoA layout, when the options ask for one.
  InterleavedParticles<Scalar, 1> array_of_structures;
  InterleavedParticles<Scalar, kLanesPerLine<Scalar>> blocked_structures;
  /// Jacobi's apply pass: the awake particles as [begin, end) ranges of at most a task's size.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> particle_tasks;
  RunnerHandle runner;
  /// The layout relaxation runs over (VerletOptions::layout, with automatic resolved).
  ParticleLayout layout = ParticleLayout::soa;
  /// Whether a stage is large enough to split across threads: slots ≥ parallel_minimum_slots.
  std::uint32_t parallel_minimum_slots = 0;
  /// Constraints of the awake islands this step (the work counter a sweep adds).
  std::uint64_t awake_constraints = 0;
  /// state.awake_generation the batches were built for (rebuilt when it changes).
  std::uint64_t built_for = ~std::uint64_t{0};
  /// The direct solver's (RelaxationSolver::direct only).
  DirectProjection<Scalar> direct;
  /// Long-range attachments (VerletOptions::long_range_attachments): per particle, the pinned
  /// particle it hangs from (the null particle: none) and the rest length of the path, m.
  std::vector<std::uint32_t> attachment_pin;
  std::vector<Scalar> attachment_length;
  /// The rattle rule (ProjectionRule::rattle): constraints whose position projection fell back
  /// to pbd since the step began (batch_projection.hpp, kStartGradientMinimumCosine). The
  /// coloured sweeps keep each slot's start gradient in the batches; the sequential sweep and the
  /// direct solver keep it here, per constraint (unit, or 0: a zero-length joint, or fallen back).
  SharedCounter fallbacks;
  std::vector<Eigen::Matrix<Scalar, 3, 1>> constraint_gradient;
  /// Joint rows (kernel/particles/joint_rows.hpp) of the awake islands, by colour and kind;
  /// the counting sort's scratch; the substep length the rows are projected with, s.
  JointRowBatches<Scalar> joint_batches;
  std::vector<std::uint32_t> joint_row_order, joint_bucket;
  Scalar joint_step = 0;
  std::uint64_t joint_built_for = ~std::uint64_t{0};  ///< state.awake_generation the joint batches hold
  /// The exact joint-tree solve (settings.verlet.joint_solve tree).
  JointTrees joint_trees;
  /// Contact rows (kernel/particles/contact_rows.hpp), coloured and batched every substep.
  ContactRowBatches<Scalar> contact_batches;
};

}  // namespace limber
