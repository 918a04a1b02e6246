// The mutable state of the Verlet method: everything that changes while stepping, in layouts/
// buffers, plus the cold data the passes and observers need. Built by compile() (compile.hpp)
// from an immutable Model; stepped by step() (step.hpp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/model/island_sleep.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/model/method_settings.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/particles/contact_rows.hpp"
#include "limber/kernel/particles/joint_rows.hpp"
#include "limber/kernel/particles/relaxation_plan.hpp"
#include "limber/kernel/threading/block_runner.hpp"
#include "limber/layouts/aligned_array.hpp"
#include "limber/layouts/constraints/distance_constraint_buffer.hpp"
#include "limber/layouts/graph/particle_ordering.hpp"
#include "limber/layouts/particles/interleaved_particles.hpp"
#include "limber/layouts/particles/particle_buffer.hpp"

namespace limber {


/// A connected set of particles (joined by constraints), stored contiguously in every buffer so
/// a pass over the awake islands is a pass over a few index ranges. Islands sleep and wake whole.
struct Island : IslandSleep {
  std::uint32_t particle_begin = 0, particle_end = 0;
  std::uint32_t constraint_begin = 0, constraint_end = 0;
  std::uint32_t limb_begin = 0, limb_end = 0;
  std::uint32_t feature_begin = 0, feature_end = 0;  ///< contact features (plane contacts)
};

/// LimbBuffer::centre of a limb without a centre particle (LimbMasses::ends).
inline constexpr std::uint32_t kNoCentre = 0xFFFFFFFF;
/// ContactFeature::limb of a ball's feature.
inline constexpr std::uint32_t kNoLimb = 0xFFFFFFFF;

/// Limbs as the particle method sees them (structure of arrays, cold: contact geometry,
/// applied forces and metrics). A limb is the segment head → tail with a cylinder or capsule
/// around it; with LimbMasses::inertia a third particle sits at its centre, held at the
/// midpoint by the half-length constraints head–centre and centre–tail (compile.hpp).
struct LimbBuffer {
  std::vector<std::uint32_t> head, tail;      ///< particle indices
  std::vector<std::uint32_t> centre;          ///< particle index, or kNoCentre
  std::vector<std::uint32_t> link_constraint; ///< index of its head–tail distance constraint
  /// The limb's own mass at each particle, kg (a particle shared by a joint also carries the
  /// other limb's share; centre_mass is 0 without a centre particle).
  std::vector<double> head_mass, centre_mass, tail_mass;
  std::vector<double> radius;                 ///< m
  std::vector<ShapeType> shape;
  /// Per limb: a sphere (a capsule of length 0), whose head and tail straddle its centre
  /// (frames::axis_length): its contacts act at the centre, their midpoint.
  std::vector<std::uint8_t> sphere;
  std::size_t size() const { return head.size(); }
};

/// A point of a limb or of a ball that can touch a plane: a sphere of `radius` about a
/// particle (ball, capsule end) or the rim of a cylinder's end disk, whose axis runs from
/// `axis_partner` to `particle`.
struct ContactFeature {
  std::uint32_t particle = 0;
  std::uint32_t axis_partner = 0;  ///< == particle for a sphere
  double radius = 0;
  bool is_disk = false;
  double restitution = 0;  ///< the feature's own (a ball's); a contact uses the larger of it and the plane's
  std::uint32_t limb = kNoLimb;  ///< the limb it belongs to (LimbBuffer index), kNoLimb for a ball
  /// A sphere limb's: a sphere of `radius` about the midpoint of `particle` and `axis_partner`.
  bool at_centre = false;
};

/// Active contacts of the current step (capacity fixed at compile: no allocation in step()).
struct PlaneContact {
  std::uint32_t feature = 0, plane = 0;
  double approach_speed = 0;    ///< normal velocity before relaxation, m/s (< 0 approaching)
  double start_separation = 0;  ///< at the previous positions, m (< 0: it began the step inside)
  double position_impulse = 0;  ///< the pushes of this (sub)step's relaxation, kg·m (≥ 0)
  double velocity_impulse = 0;  ///< the rattle rule's velocity stage so far, N·s (contact_impulse, contacts.hpp)
  bool held_by_trees = false;   ///< solved with the joint trees (tree_contacts.hpp), not by the sweeps
};
/// A ball as the particle method holds it: one particle, its own island.
struct BallParticle {
  std::uint32_t particle = 0;
  std::uint32_t island = 0;
  double radius = 0;       ///< m
  double restitution = 0;  ///< [0, 1]
};

/// A ball–limb contact as a contact plane fixed when the contact was found: normal n (limb →
/// ball), the point a of the way from head to tail, and the offset k, so that
/// C = n·(x_ball − ((1−a)·x_head + a·x_tail)) − k is the separation (< 0 overlapping).
struct BallContact {
  std::uint32_t ball = 0;  ///< VerletState::balls index
  std::uint32_t limb = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
  double axial = 0;
  double offset = 0;            ///< k, m
  double approach_speed = 0;    ///< relative normal velocity before relaxation, m/s
  double start_separation = 0;  ///< at the previous positions, m
  double position_impulse = 0;  ///< the pushes of this (sub)step's relaxation, kg·m (≥ 0)
  double velocity_impulse = 0;  ///< the rattle rule's velocity stage so far, N·s (contact_impulse, contacts.hpp)
};

/// What a particle stands for: a limb's head, tail or centre (index: Model body), the world end
/// of a joint to the world (index: Model joint), or a ball (index: Model::balls).
struct ParticleOrigin {
  enum class Kind : std::uint8_t { limb_head, limb_tail, limb_centre, world_pin, ball, limb_frame_plus, limb_frame_minus };
  std::uint32_t index = 0;
  Kind kind = Kind::limb_head;
};

/// A pinned particle moved along a path (a held point: World's kinematic targets): over the
/// next step it goes from where it is to `target` at constant velocity, substep by substep.
struct KinematicTarget {
  std::uint32_t particle = 0;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< m, world
  Eigen::Vector3d start = Eigen::Vector3d::Zero();   ///< m, where the step found it (set by step())
};

/// Work counters, accumulated over all steps (for benchmarks and the "sleeping costs nothing" test).
struct StepCounters {
  std::uint64_t particles_integrated = 0;
  std::uint64_t constraint_projections = 0;
  std::uint64_t contact_projections = 0;
};

template <typename Scalar>
struct VerletState;

/// Whether `state` steps under the rattle projection rule, (x, v) (else pbd, (x, x*)).
template <typename Scalar>
bool uses_rattle(const VerletState<Scalar>& state) {
  return state.options.relaxation.projection == ProjectionRule::rattle;
}

/// The shortest substep a float particle state takes, s. A float coordinate near 1 m resolves
/// 6·10⁻⁸ m, so a shorter substep keeps a moving particle's velocity in its last bits: on
/// chain.json (16 substeps) one step of 10⁻⁵ s among steps of 1/240 s changed the energy a
/// second later by 0.05 %, one of 10⁻⁶ s (substeps of 6·10⁻⁸ s) by 0.7 %.
inline constexpr double kMinimumFloatSubstep = 1e-6;

/// The shortest step `state` takes (step_status.hpp's guard), s: kMinimumTimeStep, and for a
/// float state substeps of at least kMinimumFloatSubstep.
template <typename Scalar>
double minimum_time_step(const VerletState<Scalar>& state);

template <typename Scalar>
struct VerletState {
  using Vector3s = Eigen::Matrix<Scalar, 3, 1>;

  // --- hot: the buffers the passes stream over ---
  ParticleBuffer<Scalar> particles;
  DistanceConstraintBuffer<Scalar> constraints;

  // --- structure (fixed at compile) ---
  std::vector<Island> islands;
  LimbBuffer limbs;
  std::vector<ContactFeature> features;
  std::vector<Plane> planes;              ///< ground first (if any), then the six bound walls
  std::vector<double> particle_mass;      ///< kg, the physical mass share even when pinned (metrics)
  std::vector<std::uint32_t> body_limb;   ///< Model body index → limb index
  /// Joint constraints and the length the gap is measured against (mean of the two limbs), m.
  std::vector<std::pair<std::uint32_t, double>> joint_constraints;
  std::vector<std::uint32_t> joint_constraint_joint;  ///< per joint_constraints entry: its joint (of the compiled Model)
  /// Frames, anchors off the limbs' ends, hinges, limits, friction and drives (joint_rows.hpp);
  /// empty for a scene of spherical joints at limb ends.
  JointRowSet joint_rows;
  /// The Model's joints and frames, to measure limits and drives (and where World writes a drive).
  JointControls joint_controls;
  std::vector<ParticleOrigin> particle_origins;
  /// Colour of each constraint (constraint_colouring.hpp; kNoColour: overflow or never moved)
  /// and the number of colours.
  std::vector<std::uint8_t> constraint_colour;
  std::uint32_t colour_count = 0;  ///< names them in outputs (particle_name, compile.hpp)
  /// Limb–limb and limb–static collision (inactive for a scene with neither).
  LimbCollisions collisions;
  std::vector<BallParticle> balls;  ///< Model::balls, in order: the last particles and islands
  /// Where motors act (Model::actuators; empty without them): each joint coordinate's joint, as
  /// compiled (serial joints through virtual links, scene/serial_links.hpp).
  CoordinateAxes coordinate_axes;

  // --- settings, resolved ---
  VerletOptions options;
  Settings settings;
  Vector3s gravity = Vector3s::Zero();

  // --- changing ---
  double time = 0;            ///< s
  double previous_time_step = 0;  ///< Δt of the last step (for the implicit velocity), s
  /// The longest recent (sub)step, s, and the time since it ended, s: a shorter substep turns its
  /// relaxation's corrections into velocity over max(h, span − age), not h
  /// (verlet/step.cpp, shortened_step_velocity).
  struct CorrectionTime {
    double span = 0, age = 0;
  } correction_time;
  std::vector<std::uint32_t> awake_islands;
  std::uint64_t awake_generation = 0;  ///< counts changes of awake_islands
  RelaxationPlan<Scalar> plan;
  std::vector<std::uint32_t> contact_particles;  ///< particles the contacts of this step move
  std::vector<PlaneContact> plane_contacts;
  std::vector<BallContact> ball_contacts;  ///< the last substep's
  ContactRowSet contact_rows;              ///< limb–limb, limb–static, ball–static: the last substep's
  // Detection's scratch (limb_contacts.cpp): per Model body (then per ball), its segment and
  // whether it is awake; per limb, a flag; the contacts found.
  std::vector<LimbSegment> limb_segments;
  std::vector<std::uint8_t> limb_awake, limb_island_awake;
  std::vector<LimbContact> limb_contacts;
  /// state.awake_generation of the broadphase pairs the collision world keeps for the step's
  /// later substeps (~0: none kept).
  std::uint64_t pairs_searched_for = ~std::uint64_t{0};
  bool ball_touched = false;  ///< a ball touched a limb in some substep of the last step
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> pending_forces;  ///< particle, N; next step
  std::vector<KinematicTarget> kinematic_targets;  ///< pinned particles only; next step, then cleared
  /// Per Model body, its body frame's orientation (body → world). A limb with frame particles
  /// reads its own (framed_orientation); a stick has no roll, so each step turns its frame by
  /// the smallest rotation that takes the old axis to the new one (parallel transport,
  /// verlet/bodies.hpp): continuous in time.
  std::vector<Eigen::Quaterniond> body_frame;
  StepReport last_report;
  StepCounters counters;
};

/// Particle p's velocity, m/s: the state's v (rattle), or (x − x*)/Δt of the last (sub)step (pbd,
/// whose velocity is implicit and first order).
template <typename Scalar>
Eigen::Vector3d particle_velocity(const VerletState<Scalar>& state, std::uint32_t p) {
  const auto& particles = state.particles;
  if (uses_rattle(state)) return particles.velocity(p).template cast<double>();
  return (particles.position(p).template cast<double>() - particles.previous(p).template cast<double>()) / state.previous_time_step;
}

/// The Model body frame's orientation of a limb with a frame (joint_rows.hpp), from its
/// particles: u = (head − tail)/|·|, v = (F⁺ − F⁻) made orthogonal to u, w = u × v, turned by the
/// limb's fixed frame_to_body. Empty for a stick, which has no roll of its own.
template <typename Scalar>
std::optional<Eigen::Quaterniond> framed_orientation(const VerletState<Scalar>& state, std::size_t body) {
  const JointRowSet& rows = state.joint_rows;
  if (rows.frame_plus.empty() || rows.frame_plus[body] == state.particles.null_particle()) return std::nullopt;
  const std::uint32_t limb = state.body_limb[body];
  const auto at = [&](std::uint32_t p) -> Eigen::Vector3d { return state.particles.position(p).template cast<double>(); };
  const Eigen::Vector3d u = (at(state.limbs.head[limb]) - at(state.limbs.tail[limb])).normalized();
  Eigen::Vector3d v = at(rows.frame_plus[body]) - at(rows.frame_minus[body]);
  v = (v - v.dot(u) * u).normalized();
  Eigen::Matrix3d frame;
  frame.col(0) = v, frame.col(1) = u.cross(v), frame.col(2) = u;
  if (!frame.allFinite()) return std::nullopt;
  return (Eigen::Quaterniond(frame) * rows.frame_to_body[body]).normalized();
}

template <typename Scalar>
double minimum_time_step(const VerletState<Scalar>& state) {
  if constexpr (std::is_same_v<Scalar, float>) {
    return std::max(kMinimumTimeStep, kMinimumFloatSubstep * state.options.relaxation.substeps);
  } else {
    return kMinimumTimeStep;
  }
}

}  // namespace limber
