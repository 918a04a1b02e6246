// The joint rows' part of relaxation (kernel/particles/joint_rows.hpp): coloured once at
// compile, batched by colour and kind when islands sleep or wake, and swept after the distance
// constraints in every sweep — colour after colour, SIMD lanes and threads inside a colour, the
// overflow last — on the SoA particle arrays. Internal to kernel/relaxation.
//
// The rows are coloured among themselves rather than with the distance constraints: a sweep
// runs the distance colours, then the joint colours. That is another Gauss-Seidel order, not
// another method, and it keeps the distance batches (and their tested bits) as they were.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Checks the options against the rows (weighted Gauss-Seidel on the SoA layout) and colours
/// them; reserves the batches. Throws std::invalid_argument naming what does not go together.
template <typename Scalar>
void prepare_joint_rows(VerletState<Scalar>& state);

/// Refills the batches with the awake islands' rows (no allocation).
template <typename Scalar>
void build_joint_batches(VerletState<Scalar>& state);

/// Starts a (sub)step of h seconds: zeroes the accumulated multipliers.
template <typename Scalar>
void begin_joint_rows(VerletState<Scalar>& state, double h);

/// One sweep of every awake row: positions (XPBD), or the rattle rule's velocity stage.
/// Returns the largest displacement (m) or velocity change (m/s).
template <typename Scalar>
double joint_position_sweep(VerletState<Scalar>& state);
template <typename Scalar>
double joint_velocity_sweep(VerletState<Scalar>& state);

}  // namespace limber
