// Contacts solved with the joint trees: a tree limb's contacts push its whole tree, with the
// mobility the tree gives the contact, instead of the limb's own particles (the pbd rule, with
// VerletSettings::joint_solve = JointSolve::tree; kernel/relaxation/README.md, "Contacts with the
// trees").
//
// Why: a contact row pushes one limb's particles and the tree, solved after it, moves the limb
// back to its joints; under a heavy body, a light limb's contact then holds only m/(M + m) of its
// push each sweep (the pile's tibias sank 13 cm into the stairs at 2 × 2). Pushed through the
// tree, the contact moves the limb *and* what hangs on it, as far as closing it needs.
//
// How: a tree call is up to four rounds (joint_tree_solve.cpp runs the stages), each a Newton
// step of the joints and the contacts together:
// 1. each awake component's Newton step of its joints is solved (its motion Δq₀ kept, not yet
//    applied) and, for a component with contacts, the diagonal of its tree's inverse Z
//    (TreeElimination::inverse_diagonal): Z_l is limb l's mobility with every joint kept;
// 2. each contact, from its separation and slip once its sides' motion so far is counted,
//    C' = C + Σ_s J_s·(Δq₀_s + Δq_s) (Δq: the round's contact motion so far), takes the position
//    impulses a contact row would with the articulated mobility in place of its particles'
//    inverse masses:
//      push λ = −C'/a_n,  a_n = Σ_s J_s Z_s J_sᵀ  (J_s: n along its point, 1 × 6),
//      friction as the rows' (accumulated, clamped to μ times the accumulated push), with
//      a_t = ½ (tr W − nᵀWn),  W = Σ_s P_s Z_s P_sᵀ  (P_s: its point's motion, 3 × 6);
//    on each side's limb the load J_sᵀλ + P_sᵀΔP_t (tree_contact_impulses); the round's pushes
//    stay ≥ 0 in sum, a later iteration taking back what an earlier one overshot;
// 3. each component solves its loads with the round's factor (one back-substitution) and adds
//    that motion to Δq, scaled down so that no contact of it moves past what it asked for
//    (several contacts on one tree, each solved alone, would push it several times over: the
//    loads are Jacobi's within a tree and across trees);
// 4. each contact keeps the impulses it took, divided by the larger of its sides' scales (at the
//    next iteration's stage 2, or the round's end).
// Stages 2–4 are four Jacobi iterations; then each component moves by Δq₀ + Δq, and the round's
// impulses join the substep's (end_tree_contact_round).
// A contact with one side static (stairs, ground) or asleep acts on one tree; one between two
// trees splits its push by their mobilities; one between two limbs of one tree (a loop: a forearm
// on its own torso) takes its exact mobility along n, the two sides' coupling through the tree
// included, from one back-substitution on the paths from its limbs to the root
// (take_loop_mobilities, in stage 1: a pack's lanes each solve one of their loops together), and
// is listed once under its tree. Rows and plane contacts
// between a tree limb and anything else (a ball, a limb outside the trees) stay in the sweeps.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"
#include "limber/kernel/relaxation/tree_packs.hpp"

namespace limber {

/// Whether the trees solve contact row `row` (every side it moves is a tree limb of an awake
/// island). False when the trees take no contacts (JointTrees::with_contacts).
template <typename Scalar>
bool held_by_joint_trees(const VerletState<Scalar>& state, const ContactRow& row);

/// A substep's start (after detection and build_contact_batches): collects the tree contacts —
/// the contact rows held_by_joint_trees, and the plane contacts of tree limbs, which it marks
/// held (the sweeps and restitution skip them) — grouped by component. h: the substep, s.
template <typename Scalar>
void gather_tree_contacts(VerletState<Scalar>& state, double h);

/// Stage 1, after the factor of `pack`'s lanes where `lanes` holds (their joint steps solved and
/// kept): each of their components' loops — a contact whose two sides are limbs of its tree —
/// measured at the positions, and its exact mobility along n, each side's share J_s·x_s of the
/// motion x that a unit push makes (a back-substitution with the factor on the paths to the
/// root; the inverse diagonal's blocks leave out how the tree couples the two sides). The lanes'
/// k-th loops are solved together (solve_pack_paths).
template <typename Scalar>
void take_loop_mobilities(VerletState<Scalar>& state, TreePack<Scalar>& pack, const LaneMask& lanes);

/// Stage 2: every tree contact's impulses and loads, from its components' joint step and
/// contact motion so far this round (JointTrees::joint_motion, load_motion) and their inverse
/// diagonals; `first` (a round's first iteration): its geometry measured afresh at the positions,
/// else the last iteration's impulses first join the round's (at the larger of its sides'
/// components' load_scale). On the relaxation's threads when the trees are.
template <typename Scalar>
void tree_contact_impulses(VerletState<Scalar>& state, bool first);

/// Stage 3, for component `component`: adds its contacts' loads to the elimination's body
/// right-hand sides (which the caller has zeroed). Returns whether there were any.
bool add_tree_contact_loads(JointTrees& trees, std::uint32_t component);

/// Stage 3, after the loads' solve: the factor by which their motion must be scaled down so that
/// no contact side of `component` moves past the motion it asked for (≥ 1).
double tree_contact_overshoot(const JointTrees& trees, std::uint32_t component);

/// A round's end: each contact's last iteration's impulses join the round's, and the round's the
/// substep's (λ and the friction impulse).
void end_tree_contact_round(JointTrees& trees);

/// The contact rows the trees pushed this substep (λ > 0), for StepReport::contacts (plane
/// contacts are counted with the step's plane contacts).
int tree_contact_rows_pushed(const JointTrees& trees);

extern template bool held_by_joint_trees<float>(const VerletState<float>&, const ContactRow&);
extern template bool held_by_joint_trees<double>(const VerletState<double>&, const ContactRow&);
extern template void gather_tree_contacts<float>(VerletState<float>&, double);
extern template void gather_tree_contacts<double>(VerletState<double>&, double);
extern template void tree_contact_impulses<float>(VerletState<float>&, bool);
extern template void tree_contact_impulses<double>(VerletState<double>&, bool);

}  // namespace limber
