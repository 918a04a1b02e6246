// Contact rows: the particle method's limb–limb, limb–static and ball–static contacts as
// unilateral constraints on up to four particles (kernel/collision/limb_contacts.hpp finds
// them each substep; kernel/relaxation/contact_relaxation.hpp colours and sweeps them).
//
// A contact found between two shapes fixes its normal n and where it lies on each limb's axis
// (a of the way from head to tail), so its separation is linear in the particles' positions:
//   C = n·Σ c_k x_k − offset ≥ 0,
// with c = (1 − a, a) on the first limb's head and tail, (−(1 − b), −b) on the second's (none for
// static geometry, whose surface point is in `offset`; 1 on the ball's particle). The projection
// is eq. 4.7 generalized to a point between particles: λ = −C / Σ w_k c_k², Δx_k = w_k c_k λ n —
// momentum-preserving, exact for the linear C (Müller et al. 2007, "Position based dynamics",
// eq. 9). Friction is static Coulomb friction on positions (Müller et al. 2020, "Detailed rigid
// body simulation with extended position based dynamics", 3.5): the contact point's tangential
// slip since the substep began, D_t, is undone while that takes at most μ times the normal
// push accumulated this substep, |Δp_t| ≤ μ λ.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "limber/layouts/constraints/contact_row_batches.hpp"

namespace limber {

/// One contact (double precision, cold: detection writes it, the batches take a copy).
struct ContactRow {
  std::array<std::uint32_t, kContactRowParticles> particle{};  ///< unused: the null particle
  std::array<double, kContactRowParticles> coefficient{};      ///< c_k (0 for unused places)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();           ///< unit
  /// What C is measured from, m: the contact's own offset plus the overlap it may keep this
  /// substep (an overlap it began with is pushed out at most at Settings::contact_recovery_speed).
  double offset = 0;
  double friction = 0, restitution = 0;
  double approach_speed = 0;  ///< n·Σ c_k v_k before relaxation, m/s (< 0 approaching)
  /// The rattle rule's velocity stage so far this substep, N·s (relaxation's push is the
  /// batches' λ; contact_impulse, kernel/collision/contacts.hpp).
  double velocity_impulse = 0;
};

/// The substep's contact rows and the colouring's scratch (capacities kept between substeps).
struct ContactRowSet {
  std::vector<ContactRow> rows;
  std::vector<std::uint8_t> colour;             ///< per row; kNoContactColour: overflow; kTreeContact
  std::vector<std::uint64_t> particle_colours;  ///< per particle: the colours that already move it
  std::vector<std::uint32_t> order;             ///< rows sorted by colour, static ones first (scratch)
  std::uint32_t colour_count = 0;
  bool empty() const { return rows.empty(); }
};

/// ContactRowSet::colour of a row in the overflow, and of one the joint trees solve.
inline constexpr std::uint8_t kNoContactColour = 0xFF;
inline constexpr std::uint8_t kTreeContact = 0xFE;
/// Colours the greedy colouring may open (one bit each in particle_colours).
inline constexpr std::uint32_t kMaxContactColours = 64;

}  // namespace limber
