// Divergence that cannot hide: the checks past the per-island speed guard (island_sleep.hpp),
// which sees how fast points move but not a limb spinning about its own axis, nor a state that
// gained energy slowly, nor joints pulled apart. Every method is observed alike (observers.hpp),
// so one check serves them all; the World and the command line run it after every step.
//
// A run has diverged when, after a step,
// - a number of the state is not finite: its energy, momentum, centre of mass, a joint gap or a
//   link's stretch
//   (a non-finite position, velocity, angular velocity or orientation reaches one of them);
// - its energy (kinetic, linear and angular, plus potential) has risen above the energy it
//   started with by more than kDivergenceEnergyFactor times the scene's energy scale: the work
//   gravity does on its mass across its extent, plus the kinetic energy it started with (a
//   thrown ball's); without loads and drives no method may gain energy at all, so the bound
//   only leaves room for what pushes, drives and moving pins put in;
// - a joint gap, or a particle limb's stretch (Observation::max_link_stretch: its head–tail
//   distance is a constraint like a joint's), has grown past kDivergenceJointGap (a whole link
//   length). Unconverged relaxation on a long chain can leave the joints closed and the links
//   several times their length, gaining energy, with every number finite.
#pragma once

#include "limber/kernel/metrics/observation.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/step_status.hpp"

namespace limber {

/// How many energy scales a run may gain before it has diverged (a stable run gains none).
inline constexpr double kDivergenceEnergyFactor = 100;
/// The largest joint gap or link stretch, relative to the link length, of a run that holds
/// together: a whole link. The stiff springs' default joints sag to 0.5–0.6 of a short link (a
/// neck under a head) in the shipped ragdolls without coming apart; a spring that lets go
/// stretches to many.
inline constexpr double kDivergenceJointGap = 1.0;

/// A run that holds together can still be poor: the command line's summary flags (and does not
/// fail) one that ends with a joint gap or link stretch past kAccuracyJointGap of a link, or
/// with its energy risen past kAccuracyEnergyGain of the scene's energy scale (DivergenceBounds):
/// without loads and drives no method should gain energy, and a converged solve holds joints
/// closed to far less than a percent once an impact has passed.
inline constexpr double kAccuracyJointGap = 0.01;
inline constexpr double kAccuracyEnergyGain = 0.01;

/// What a run is measured against, fixed when it starts (or its model changes).
struct DivergenceBounds {
  double start_energy = 0;  ///< J, kinetic + potential at the start
  double energy_scale = 0;  ///< J, > 0: M·|g|·max(extent, 1 m) + the start's kinetic energy, at least 1 J
};

/// The bounds of `model` from its observation at the start.
DivergenceBounds divergence_bounds(const Model& model, const Observation& start);

/// Which bound `now` is past: diverged_non_finite, diverged_energy or diverged_joint_gap; ok when none.
StepStatus check_divergence(const Observation& now, const DivergenceBounds& bounds);

}  // namespace limber
