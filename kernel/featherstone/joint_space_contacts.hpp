// Contacts of the Featherstone method, answered through the joint-space inertia: the impulsive
// form of the equations of motion, H·Δv = Jᵀι (Featherstone 2008, chapter 11, impact) — an
// impulse on one link moves the whole tree (Mirtich 1996, "Impulse-based dynamic simulation of
// rigid body systems", PhD thesis, Berkeley; Kokkevis 2004, "Practical physics for articulated
// characters", GDC).
//
// The contacts are found on the rigid bodies the state keeps beside (q, v)
// (detect_rigid_contacts, kernel/collision/rigid_contacts.hpp): body a touches body b (b: a
// plane, or another body) at p with normal n from b to a. Their response:
//
// When. Under RK4 the step keeps the thesis's loop (figure 2.5): move, then collide — the
// contacts are found after the integrator moved the bodies and answered at the new pose. Under
// semi-implicit Euler they are solved before the move, as MuJoCo's step (mj_step: constraint
// forces in the velocity update) and Box2D's solve them ("Before the move", below). The thesis's
// loop moves a resting body by gΔt² into the ground every step, and its push-out and re-projection
// took it back every step (a CRBA each); the slip a step moved on a slope was stopped in v but
// not taken back from q, so static friction crept (14 mm/s on a 20° slope at 1/240 s); and a
// landing limb overlapped by up to a step's travel before anything answered it (11.4 mm on the
// ragdoll's side landing). Before the move none of the three happens.
//
// Responses. Once a step, the composite-rigid-body algorithm writes H into the sparsity of its
// tree and it is factored as LᵀDL (joint_space_factor.hpp; MuJoCo's mj_crb and mj_factorM) —
// before the move, by the velocity update of an island a contact touches (below). A
// contact's rows J_c (3 × nv: the relative velocity of its points, a's minus b's, along its
// normal and two tangents, contact_frame) are the generalized impulses of unit impulses at p on
// every joint k from each body to the root (τ_k = S_kᵀ f, Table 5.1's inward pass), each taken in
// world coordinates as the geometric Jacobian's column (u × (p − o) for a hinge about the world
// axis u through o) and turned into the contact's frame:
// non-zero only on the two bodies' paths, and so are its half rows Y_c = L⁻ᵀ J_cᵀ (MuJoCo's
// half-solve). Its
// collision matrix is K_c = J_c H⁻¹ J_cᵀ = Y_cᵀ D⁻¹ Y_c (3×3, the contact's frame: the change of
// the relative velocity per unit impulse +J on a and −J on b; its normal-normal entry is the
// inverse of the contact's effective mass along the normal, J_n H⁻¹ J_nᵀ). A limit row (below) is a row on its joint's
// velocities, with half rows on its joint's path. An impulse ι moves the joints by
// Δv = H⁻¹ J_cᵀ ι = L⁻¹ y with y = D⁻¹ Y_c ι: the passes add y on the row's path alone and read a
// row's motion as J x + Yᵀ y (x: v, or the push-out's displacement), and x takes every impulse
// at the passes' end as L⁻¹ y, one forward pass. So an impulse costs its paths, not its islands.
//
// Constraint space. The limit rows of an island, solved together (below), need their Delassus
// matrix A = J H⁻¹ Jᵀ = Y D⁻¹ Yᵀ: it is formed once a step per island from their half rows
// (Carpentier et al. 2021, "Proximal and sparse resolution of constrained dynamic equations":
// the Delassus matrix through the factor). The contacts are not in it: a contact's impulse costs
// its paths through y, where a Delassus matrix over an island's contacts costs their count
// squared times a path to form: with one (tried), a 200-link chain lying on the ground (400
// contacts) took 2.9× the step of answering each through y, humanoid.xml 1.08× and
// 22_humanoids.xml 1.14× (bench/models.md).
//
// Groups. The islands a step's contacts join (a contact between two islands joins them; a limit
// row stays in its own) form groups, and each group is solved whole — H's factor on its islands,
// its blocks, impulses, push-out and re-projection — apart from every other: its rows touch only
// its islands' coordinates, so the groups' answers do not depend on each other, nor on their
// order. They are the tasks of FeatherstoneOptions::threads (the same bits for any thread count,
// and as when all were solved in one sweep); the groups in the order of their first islands, the
// blocks of each in the contacts' order, then its islands' limit rows. A group whose push-out
// moves nothing is not re-projected (until this design the whole tree was, when any group
// moved; the same motion but for round-off). Islands no contact or limit row touches cost
// nothing here.
//
// Impulses. Projected Gauss–Seidel on the contacts' rows (kernel/numerics/contact_projection.hpp,
// the one step of a contact the Lagrange method's contacts take too), a fixed number of passes
// (RigidScene::contact_iterations) over the group's contacts, then its limit rows (below): each
// contact's impulse λ (its frame: normal, t₁, t₂) is accumulated — its normal part λ_n ≥ 0 moved
// until the normal speed reaches its target, and taken back when a neighbour's impulse did the
// work — and its friction is the impulse within Coulomb's disc |λ_t| ≤ μλ_n that lowers the
// tangential rows' energy most: the slip stopped through K's tangent block, or on the disc's
// edge the friction that opposes the slip it leaves (maximal dissipation). The target: e times
// the approach before the impulses for a bounce (e set to 0 for contacts that approached slower
// than 2|g|Δt: resting contacts stay at rest), else 0 — before the move, −gap/Δt for a contact
// still apart (it may close its gap in the step and no more). A change that moves no speed by
// kSlowestApproach (10⁻⁶ m/s) is not applied, and a pass that applies none ends them. So the
// passes converge to the Signorini–Coulomb answer (tested to 10⁻⁴ m/s), which sequential
// impulses that only push — this design's predecessor, until this one — did not: they stopped
// 17–23 % of the constraint solve's change away from it on humanoid.xml (kinetic-energy norm),
// however many passes; projected Gauss–Seidel is 4 % away after 8 passes while it moves, 0.5 %
// at rest (bench/models.md).
//
// Warm start. A step starts each contact from the impulse the last step's nearest contact of the
// same two bodies ended with, within 1 cm (Box2D's persistent contacts, matched by place where
// Box2D matches feature ids; MuJoCo warm-starts from the last step's accelerations), and each
// limit row from its own last impulse (JointLimitRow::key), both scaled by the ratio of the steps.
// A resting scene begins at its answer: one pass is 3·10⁻⁵ of the correction from it, where one
// cold pass misses by 28 % (tested on humanoid.json lying down). Without the limit rows' warm
// start the contacts converged slowly wherever a joint rested on its limit: every resting step
// re-found how the load divides between them.
//
// Energy. An accumulated impulse can pass what stops its rows (a warm start not yet taken back,
// a bounce its neighbours reached first), so the impulses' change of kinetic energy
// λᵀJv + ½λᵀAλ (through the factor) is measured once the passes end, and a group whose impulses
// would add energy has them all scaled back along the line to none until they add none (which
// keeps every impulse in its cone; MuJoCo keeps a warm start only when it costs less than a cold
// one). Tested: the impulses never add energy, with bounces, over 2 s of a thrown chain and the
// knocked humanoid; and with one pass a step, where the warm start is not taken back (the thrown
// chain gained 0.75 % of its kinetic energy in a step without the scaling).
//
// Penetration. Then a position pass through the same effective masses pushes overlaps out: each
// contact's target is its depth, at most the step's approach plus
// Settings::contact_recovery_speed·Δt (an initial overlap is not flung out); projected
// Gauss–Seidel over the contacts on the linearized map from a joint-space displacement
// δ = H⁻¹Jᵀλ (λ ≥ 0, accumulated per contact) to the contact points' motion, the same passes;
// then q ← q ⊕ δ (displace_positions) on the group's islands. No velocity bias (Baumgarte) is
// added; but v holds relative velocities in the child frames the push-out turned, so v is
// re-projected: the velocities that keep every body's motion in its own frame as closely as the
// joints allow at the new pose, in the kinetic-energy metric, v = H⁻¹ (Σ J_iᵀ I_i v_i + A v) with
// the armature's momentum A v: an H-orthogonal projection, which never adds kinetic energy —
// keeping v instead would swing a limb's fast spin about its axis onto its neighbours, and can add
// kinetic energy (up to 60 % in one step of the tests' scenes). It is taken as a correction of v
// through H's factor at the new pose (the CRBA and LᵀDL again, on the islands the push-out moved):
// an inward pass and a back-substitution. (Until this design an ABA with v = 0, g = 0 gave it, and
// before that it left A v out: each push-out slowed the joints with armature by about
// a/(a + their inertia).) The rigid bodies are refreshed.
//
// Before the move (semi-implicit Euler; step.hpp). The step finds the contacts at its start pose,
// across the gaps the step may close (RigidScene::speculative_time: each body reaches
// Δt·(|v| + |ω|·arm + |g|Δt), at most 5 cm; a resting body a quarter of a millimetre at 1/200 s,
// so a speculative contact does not join islands that rest apart) — a gap's depth negative —
// and sweeps the balls' paths of the last step (rigid_contacts.hpp). Then each island's velocity
// update v ← v + h·v̇(q, v) (its last substep's; the earlier substeps move q as before; for an
// island a contact touches, MuJoCo's way: H + h·G by the composite-rigid-body algorithm, G the
// drives' gains below, its factor, the bias forces by recursive Newton–Euler and one solve,
// factored_forward_dynamics, whose factor the constraints then take: an articulated-body pass
// beside the constraints' own CRBA and factor cost humanoid.xml 9–11 % more a step), the
// constraints on that v at the start pose as above — a contact still apart may close its gap in
// the step and no more (Catto's speculative contacts); a bouncing one (e > 0) bounces from where
// it is, as in Box2D — and only then q ← q ⊕ h·v. What overlap is left (a landing the reach missed,
// the passes' tolerance) the push-out takes at the start pose as a displacement that no velocity
// keeps (split impulses, Catto's and Bullet's), once past 2·kRestingSlop (0.2 mm) back to
// kRestingSlop (0.1 mm): a step's approach in full and older overlap at the recovery speed, as
// after the move. It joins h·v in the move and, when it moved anything, v is re-projected at the
// new pose as above. A limit row's push-out holds what is left of its gap after h·v moves it
// (C + h·row·v), and drift below 10⁻³·kRestingSlop is left to the next push. Rows are chosen by v
// before the impulses; when the impulses drive a joint at a limit the rows left out, the step is
// solved again from the free velocity with that row too (an impact's step): no push-out after
// the move would take it back. So a resting humanoid is pushed out in 10 % of its steps (nearly
// every step before), and humanoid.xml's step is 1.29× faster.
// The constraints before the move are solved against H + h·G, not H (islands without a drive
// have G = 0): the stable PD's drive force is taken at the velocity the step ends with, and the
// impulses change that velocity, so the drive answers them within the step as an implicit
// spring-damper (until this design the drives' force was held at the velocity before the
// impulses, and a driven joint the contacts stopped pushed on at the force of its unhindered
// motion).
//
// Joint limits. Each limit is an inequality C ≥ 0 on one joint coordinate x (the Model's, as
// kernel/model/joint_coordinates.hpp measures it): x − min ≥ 0, max − x ≥ 0, or for a spherical
// joint's cone swing_max − θ ≥ 0. Its row is ∂C/∂v on the joint's own velocities: ±1 for a
// revolute or prismatic joint (signed by which way the tree holds the joint); for a spherical
// joint, with ω the outboard's angular velocity relative to the inboard (inboard frame), c the
// cone axis, a the outboard's axis now, the swing θ = acos(c·a) has θ̇ = ω·(c × a)/|c × a| (the
// axis turning the cone's axis to the outboard's), and the twist about c (joint_coordinates.hpp)
// has ψ̇ = ω·(c + a)/(1 + c·a) (the outboard's axis plus the swing's turn about it; a where
// a = c) — each carried onto the joint's velocity coordinates (ω of
// the tree child relative to its parent, child frame). A row joins the contacts' passes, after
// the integrator, when it is violated or within 0.02 (rad or m) plus two steps of its approach of
// its limit: an accumulated impulse λ ≥ 0 along the row through H⁻¹ keeps
// row·v ≥ −max(C, 0)/Δt — restitution 0, and a limit not yet reached lets the joint arrive at it
// exactly at the step's end (Catto's speculative contacts). Then the push-out takes the rows
// with the contacts: a violation is pushed out in full (it is always the solver's: the Model's
// poses are inside every limit), and a row inside its limit is not pushed past it. In each pass
// an island's rows are solved together, after its contacts, in constraint space: their block of
// A and an active-set solve of their complementarity problem (kernel/numerics/active_set.hpp;
// joint_space_limits.cpp, "Holding rows") holds them on their targets to round-off — rows that
// would pull are released, rows pushed past are held, at most 8 rounds. One by one,
// Gauss–Seidel took hundreds of passes on neighbouring joints at their limits; a penalty on H's
// joint blocks, refactored per round (before this), cost a factor a round.
//
// Drives and friction, before the integrator (joint_control_forces), as forces held over the
// step: a drive is the stable PD of Tan, Liu & Turk (2011, "Stable proportional-derivative
// controllers", IEEE CG&A): its force k·(target − x − h·ẋ⁺) + c·(target_velocity − ẋ⁺) is
// taken at the velocity ẋ⁺ the step ends with, found with the dynamics, which adds the
// armature h·(k·h + c) to the driven coordinates' D_i in the articulated-body algorithm — one
// ABA, O(n), unconditionally stable in k and c (or to H's diagonal in the factor, for an island
// a contact touches before the move). Friction then gives each joint the impulse j that
// stops its predicted velocity through that same inertia, clamped to |j| ≤ friction·h (per DOF;
// a spherical joint's 3-vector by its norm, against the velocity it slides at), an island's
// joints together (stuck joints held by a penalty on their block of H + h·G, refactored;
// sliding ones at the bound), and holds j/h over the step — so a joint friction holds does not
// creep, whatever the integrator.
#pragma once

#include <vector>

#include "limber/kernel/featherstone/featherstone_state.hpp"

namespace limber {

/// Impulses, then push-out, for state.contacts (found by detect_rigid_contacts on the refreshed
/// rigid bodies) and the joint limits' rows, group by group (above) on the state's threads; dt is
/// the step's. Leaves (q, v), state.kinematics and the rigid bodies consistent. Allocates
/// nothing once the scratch has met the step's groups (compile reserves for a group per island).
void resolve_joint_space_contacts(FeatherstoneState& state, double dt);

/// Whether the step solves the contacts and limits on the velocity update, before the positions
/// move (semi-implicit Euler: "Before the move" above), or after the move (RK4: the thesis's loop).
inline bool constraints_before_move(const FeatherstoneState& state) {
  return state.options.integrator == Integrator::semi_implicit_euler;
}

/// Before the move: island `island`'s positions move by its last substep times its constrained
/// velocity, q ← q ⊕ h·v, then by its group's push-out (with the re-projection of v), and its
/// rigid bodies are refreshed. Touches only its bodies' and coordinates' entries.
void advance_positions(FeatherstoneState& state, std::size_t island);

/// v̇ = (H + diag(armature))⁻¹ (τ − C(q, v)) on island `island`'s coordinates of `accelerations`
/// (nv), τ = joint_forces (nv), armature nv values or null, at the poses and velocities in
/// state.kinematics (forward_kinematics of the current q and v, as between steps): the
/// mass matrix by the composite-rigid-body algorithm, its LᵀDL factor, the bias forces by
/// recursive Newton–Euler (MuJoCo's mj_crb, mj_factorM, mj_rne, mj_solveM) — forward_dynamics'
/// answer to round-off. Before the move, for an island a contact touches: the factor it leaves
/// in state.contact.factor is the one the constraints are then solved against
/// (state.contact.factored), so the step factors H once. v̇ not finite when H + diag(armature)
/// was not positive definite (a state gone non-finite). Allocates nothing.
void factored_forward_dynamics(FeatherstoneState& state, std::size_t island, const Eigen::VectorXd& joint_forces, const double* armature,
                               Eigen::VectorXd& accelerations);

/// Applies only the impulses of resolve_joint_space_contacts (no push-out) and refreshes the
/// rigid bodies: for tests of the impulses' energy.
void apply_joint_space_impulses(FeatherstoneState& state, double dt);

/// The pose of Model body `body`'s frame (joint_coordinates' FramePose) from state.kinematics.
FramePose model_frame_pose(const FeatherstoneState& state, std::size_t body);

/// The joint forces (nv) of a step of h seconds from (q, v) into state.controls.forces: `loads`
/// (nv, the applied loads and drag as joint forces) plus the drives' stable-PD forces and the
/// joints' friction (see above), read from state.joint_controls, island by island (an awake
/// island without either takes the loads). Returns whether any awake island has a drive or
/// friction. Reads the poses in state.kinematics, which must be those of q (as they are between
/// steps).
/// Allocates nothing.
bool joint_control_forces(FeatherstoneState& state, const Eigen::VectorXd& loads, double h);
/// The same for island `island` alone (its coordinates of the forces; false, writing nothing, when
/// it has no drive or friction). Islands may run on different threads unless the scene has joint
/// friction (FeatherstoneState::joint_friction), whose factors they share. `through_factor`: the drives' dynamics by factored_forward_dynamics (which leaves the
/// island's H + h·G factored for the constraints) instead of the articulated-body algorithm.
bool joint_control_forces(FeatherstoneState& state, const Eigen::VectorXd& loads, double h, std::size_t island, bool through_factor);

/// τ = Σ J_iᵀ f_i: the joint forces (nv) equivalent to spatial forces f_i on the tree bodies
/// (body coordinates, at the body's origin; `body_forces`, one per tree body, consumed: zeroed),
/// by the inward pass of recursive Newton–Euler (Table 5.1): τ_i = S_iᵀ f_i, f_λ += λX_i* f_i.
/// Reads state.kinematics.parent_to_body.
void joint_forces_of_body_forces(const FeatherstoneState& state, std::vector<SpatialVector>& body_forces,
                                 Eigen::VectorXd& joint_forces);
/// The same for the tree bodies of `range` alone (their forces and coordinates).
void joint_forces_of_body_forces(const FeatherstoneState& state, std::vector<SpatialVector>& body_forces, Eigen::VectorXd& joint_forces,
                                 BodyRange range);

}  // namespace limber
