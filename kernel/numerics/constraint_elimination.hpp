// The constraint-space tree solve: (J W Jᵀ + α̃) μ = r for particles joined by distance
// constraints of one row each, the unknowns the multipliers alone.
//
// Two constraints couple only where they share a particle b, by w_b·s₁s₂·n₁·n₂ (w the particle's
// inverse mass or weight, n a constraint's unit direction, s = +1 on its particle i, −1 on j);
// a constraint's diagonal is (w_i + w_j)·n·n + α̃. On a chain the matrix is tridiagonal. On a tree
// of particles, eliminating the constraints leaves first (each before the constraint above its
// inboard particle: TreeOrdering's order) creates no fill: a constraint's neighbours still
// standing when it goes are the other constraints at its inboard particle, which already couple
// with one another. So each particle keeps one small dense block, its *front*: the couplings of
// its constraints (the ones below it in eliminated order, then the one above it last), and the
// elimination is a dense LDLᵀ of each front in turn, O(m²) a constraint for a front of m. A
// chain's fronts are 2 × 2: some 25 operations a link to factor and 6 to solve, against the
// 3 × 3 particle blocks of the body–constraint form (tree_elimination.hpp), which eliminates the
// same system through each particle's full mass block.
//
// The factor depends on the directions, weights and compliances only; a solve takes any
// right-hand side (a chord iteration, or the velocity stage of the same rows). Fronts are limited
// to kMaxFront constraints (a particle with more, such as a star's hub, leaves its component to
// the body–constraint form): a front's cost grows as its size cubed.
//
// Sources: the multifrontal view of sparse Cholesky (Duff & Reid 1983; Liu, "The multifrontal
// method for sparse matrix solution", SIAM Review 34, 1992), on the constraint graph of a tree,
// whose fronts are its particles' stars; the system is XPBD's (Macklin, Müller, Chentanez 2016,
// eq. 18) solved for all constraints at once, as in Deul et al. 2018.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/numerics/tree_elimination.hpp"

namespace limber {

template <typename Scalar>
class ConstraintElimination {
 public:
  /// Most constraints at one particle for its component to be solved here.
  static constexpr int kMaxFront = 8;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;

  /// Takes the body–constraint ordering (order_tree over the particles as bodies) and each
  /// constraint's bodies on its J's + side (body_i) and − side (body_j), −1 for the world.
  /// Every constraint has one row. Allocates; nothing else does.
  void assign(const TreeOrdering& ordering, std::size_t body_count, std::span<const std::int32_t> body_i,
              std::span<const std::int32_t> body_j);

  /// Whether every particle of component `index` has at most kMaxFront constraints.
  bool solvable(std::size_t index) const { return solvable_[index] != 0; }

  /// Factors the component `index`: weight(body) its particle's w (1/kg, positive),
  /// direction(constraint) its unit n (the row J = ±nᵀ), compliance(constraint) its α̃ (≥ 0,
  /// 1/kg). Returns false when a pivot is not positive (some weight not positive, or not finite).
  template <typename Weight, typename Direction, typename Compliance>
  bool factor(std::size_t index, Weight&& weight, Direction&& direction, Compliance&& compliance);

  /// Solves the factored component `index` for the right-hand side in multiplier() of its
  /// constraints, in place: afterwards multiplier(c) = μ_c, (J W Jᵀ + α̃) μ = r.
  void solve(std::size_t index);

  Scalar& multiplier(std::size_t constraint) { return work_[constraint]; }
  Scalar multiplier(std::size_t constraint) const { return work_[constraint]; }

 private:
  // Per constraint, in eliminated order within each component: what its elimination reads.
  struct Step {
    std::uint32_t constraint = 0;
    std::uint32_t below_pivot = 0;      // its diagonal entry in the front below (index in coupling_)
    std::uint32_t above_front = 0;      // the front above: first entry in coupling_, first member
    std::uint32_t above_members = 0;
    std::uint8_t place = 0, size = 0;   // its place in the front above, the front's size (0: the world)
  };
  // Entry (row, column), row ≥ column, of the lower triangle starting at `first`.
  static std::size_t entry(std::uint32_t first, int row, int column) {
    return first + static_cast<std::size_t>(row * (row + 1) / 2 + column);
  }

  std::int32_t body_count_ = 0;
  std::vector<TreeOrdering::Component> components_;  // ranges of steps_ and of bodies_
  std::vector<std::uint32_t> body_begin_;             // per component: its first in bodies_
  std::vector<Step> steps_;
  /// Per body of each component: the body, its front's first entry and first member, its size.
  struct Front {
    std::uint32_t body = 0, first = 0, members = 0;
    std::uint8_t size = 0;
  };
  std::vector<Front> bodies_;
  std::vector<std::uint32_t> members_;  // fronts' constraints: below in eliminated order, then above
  std::vector<Scalar> member_sign_;     // their rows' sign on the front's body
  std::vector<Scalar> coupling_;        // the fronts: couplings, then after factor() L's columns
  std::vector<Scalar> inverse_pivot_;   // per constraint: 1/D
  std::vector<Scalar> work_;            // per constraint: right-hand side, then μ
  std::vector<std::uint8_t> solvable_;  // per component
};

template <typename Scalar>
template <typename Weight, typename Direction, typename Compliance>
bool ConstraintElimination<Scalar>::factor(std::size_t index, Weight&& weight, Direction&& direction, Compliance&& compliance) {
  // Each particle's front: w_b·s_p·s_q·n_p·n_q.
  for (std::uint32_t k = body_begin_[index]; k < body_begin_[index + 1]; ++k) {
    const Front& front = bodies_[k];
    const Scalar w = weight(static_cast<std::size_t>(front.body));
    for (int p = 0; p < front.size; ++p) {
      const std::uint32_t c_p = members_[front.members + static_cast<std::uint32_t>(p)];
      const Vector3 n_p = (w * member_sign_[front.members + static_cast<std::uint32_t>(p)]) * direction(c_p);
      for (int q = 0; q <= p; ++q) {
        const std::uint32_t c_q = members_[front.members + static_cast<std::uint32_t>(q)];
        coupling_[entry(front.first, p, q)] = member_sign_[front.members + static_cast<std::uint32_t>(q)] * n_p.dot(direction(c_q));
      }
    }
  }
  // The constraints, leaves first: each pivot D = α̃ + its entry in the front below (final) and
  // above (updated by its earlier siblings); then the rest of the front above loses its column.
  bool definite = true;
  const TreeOrdering::Component& range = components_[index];
  for (std::uint32_t k = range.begin; k < range.end; ++k) {
    const Step& step = steps_[k];
    Scalar pivot = compliance(step.constraint) + coupling_[step.below_pivot];
    if (step.size > 0) pivot += coupling_[entry(step.above_front, step.place, step.place)];
    definite = definite && pivot > Scalar(0);
    const Scalar inverse = Scalar(1) / pivot;
    inverse_pivot_[step.constraint] = inverse;
    const int column = step.place;
    for (int row = column + 1; row < step.size; ++row) {
      const Scalar scaled = coupling_[entry(step.above_front, row, column)] * inverse;
      for (int other = column + 1; other <= row; ++other) {
        coupling_[entry(step.above_front, row, other)] -= scaled * coupling_[entry(step.above_front, other, column)];
      }
    }
    for (int row = column + 1; row < step.size; ++row) coupling_[entry(step.above_front, row, column)] *= inverse;
  }
  return definite;
}

}  // namespace limber
