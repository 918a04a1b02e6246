// The constraint-space tree solve: (J W Jᵀ + α̃) μ = r for particles joined by distance
// constraints (one row, J = ±nᵀ on its two particles) and zero-length joints (three rows,
// J = ±E), the unknowns the multipliers alone.
//
// Two constraints couple only where they share a particle b, by w_b·s₁s₂·G₁ᵀG₂ (w the particle's
// inverse mass or weight, G a constraint's n or E, s = +1 on its particle i, −1 on j); a
// constraint's diagonal block is (w_i + w_j)·GᵀG + α̃. On a chain of distance constraints the
// matrix is tridiagonal. On a tree of particles, eliminating the constraints leaves first (each
// before the constraint above its inboard particle: TreeOrdering's order) creates no fill: a
// constraint's neighbours still standing when it goes are the other constraints at its inboard
// particle, which already couple with one another. So each particle keeps one small dense
// matrix, its *front*: the couplings of its constraints' rows (the constraints below it in
// eliminated order, then the one above it last). The elimination is a block LDLᵀ of each front
// in turn, O(R²) a constraint for a front of R rows. A chain's fronts are 2 × 2: some 25
// operations a link to factor and 6 to solve, against the 3 × 3 particle blocks of the
// body–constraint form (tree_elimination.hpp), which eliminates the same system through each
// particle's full mass block.
//
// The factor depends on the directions, weights and compliances only; a solve takes any
// right-hand side (a chord iteration, or the velocity stage of the same rows). Fronts are limited
// to kMaxFrontRows rows (a particle with more, such as a star's hub, leaves its component to the
// body–constraint form): a front's cost grows as its size cubed.
//
// Values are numbers (float, double) or SIMD lanes of numbers (xsimd::batch): with lanes, each
// lane is an instance of the same shape (a rope of a forest, a ragdoll of a crowd), and lane k
// gives the bits the same code gives on lane k's numbers alone (lane_blocks.hpp: one operation
// sequence per entry, no Eigen reductions). The shape (assign) is shared; the values are not.
//
// Sources: the multifrontal view of sparse Cholesky (Duff & Reid 1983; Liu, "The multifrontal
// method for sparse matrix solution", SIAM Review 34, 1992), on the constraint graph of a tree,
// whose fronts are its particles' stars; the system is XPBD's (Macklin, Müller, Chentanez 2016,
// eq. 18) solved for all constraints at once, as in Deul et al. 2018.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "limber/kernel/numerics/lane_blocks.hpp"
#include "limber/kernel/numerics/small_cholesky.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"

namespace limber {

template <typename Scalar>
class ConstraintElimination {
 public:
  /// Most rows of the constraints at one particle for its component to be solved here: eight
  /// distance constraints, or a limb's link and six zero-length joints.
  static constexpr int kMaxFrontRows = 19;
  /// A direction: an Eigen vector of numbers, or a LaneBlock of lanes (one unit vector a lane).
  using Vector3 = Block<Scalar, 3, 1>;

  /// Takes the body–constraint ordering (order_tree over the particles as bodies), each
  /// constraint's bodies on its J's + side (body_i) and − side (body_j), −1 for the world, and
  /// its rows (1: a distance constraint, 3: a zero-length joint). Allocates; nothing else does.
  void assign(const TreeOrdering& ordering, std::size_t body_count, std::span<const std::int32_t> body_i,
              std::span<const std::int32_t> body_j, std::span<const std::uint8_t> rows);

  /// Whether every particle of component `index` has at most kMaxFrontRows rows.
  bool solvable(std::size_t index) const { return solvable_[index] != 0; }

  /// Factors the component `index`: weight(body) its particle's w (1/kg, positive),
  /// direction(constraint) the unit n of a one-row constraint (J = ±nᵀ; not called for three
  /// rows), compliance(constraint) its α̃ (≥ 0, 1/kg, on each of its rows): each a Scalar (a
  /// Vector3 of Scalars), lanes and all. Returns false when a pivot block is not positive
  /// definite in some lane (a weight not positive, or not finite).
  template <typename Weight, typename Direction, typename Compliance>
  bool factor(std::size_t index, Weight&& weight, Direction&& direction, Compliance&& compliance);

  /// Solves the factored component `index` for the right-hand side in multiplier() of its
  /// constraints' rows, in place: afterwards multiplier(c, row) = μ, (J W Jᵀ + α̃) μ = r.
  void solve(std::size_t index);

  Scalar& multiplier(std::size_t constraint, int row = 0) { return work_[row_begin_[constraint] + static_cast<std::uint32_t>(row)]; }
  Scalar multiplier(std::size_t constraint, int row = 0) const { return work_[row_begin_[constraint] + static_cast<std::uint32_t>(row)]; }
  int rows(std::size_t constraint) const { return static_cast<int>(row_begin_[constraint + 1] - row_begin_[constraint]); }

  /// Bytes of the arrays factor() and solve() read or write, every component's: what a factor
  /// and a solve of everything must move at least once (the bandwidth bound of bench/chains.md).
  std::size_t storage_bytes() const;

 private:
  // Per constraint, in eliminated order within each component: what its elimination reads.
  struct Step {
    std::uint32_t constraint = 0;
    std::uint32_t below_front = 0;  // the front below: its first entry in coupling_
    std::uint32_t above_front = 0;  // the front above: its first entry in coupling_ and first row in front_row_
    std::uint32_t above_rows = 0;
    std::uint8_t place = 0, size = 0;  // its first row in the front above, the front's rows (0: the world)
    std::uint8_t rows = 1, below_size = 0;
  };
  /// Per body: its front's first entry in coupling_, first member and first row in
  /// members_/front_row_, its members and rows.
  struct Front {
    std::uint32_t body = 0, first = 0, members = 0, rows_begin = 0;
    std::uint8_t count = 0, size = 0;
  };
  // Entry (row, column), row ≥ column, of the lower triangle starting at `first`.
  static std::size_t entry(std::uint32_t first, int row, int column) {
    return first + static_cast<std::size_t>(row * (row + 1) / 2 + column);
  }
  template <int Rows>
  void eliminate(const Step& step, Scalar compliance, bool& definite);
  template <int Rows>
  void substitute_forward(const Step& step);
  template <int Rows>
  void substitute_back(const Step& step);

  std::int32_t body_count_ = 0;
  std::vector<TreeOrdering::Component> components_;  // ranges of steps_
  std::vector<std::uint32_t> body_begin_;             // per component: its first in bodies_
  std::vector<Step> steps_;
  std::vector<Front> bodies_;
  std::vector<std::uint32_t> members_;  // fronts' constraints: below in eliminated order, then above
  std::vector<Scalar> member_sign_;     // their rows' sign on the front's body
  std::vector<std::uint32_t> front_row_;  // fronts' rows: each one's index in work_
  std::vector<std::uint32_t> row_begin_;  // per constraint: its first row in work_ (and one past the last)
  std::vector<std::uint32_t> pivot_begin_;  // per constraint: its D⁻¹ (rows × rows) in inverse_pivot_
  std::vector<Scalar> coupling_;       // the fronts: couplings, then after factor() L's columns
  std::vector<Scalar> inverse_pivot_;  // per constraint: D⁻¹, row-major
  std::vector<Scalar> work_;           // per row: right-hand side, then μ
  std::vector<std::uint8_t> solvable_;  // per component
};

template <typename Scalar>
template <typename Weight, typename Direction, typename Compliance>
bool ConstraintElimination<Scalar>::factor(std::size_t index, Weight&& weight, Direction&& direction, Compliance&& compliance) {
  // Each particle's front: w_b·s_p·s_q·(G_p column a)·(G_q column b), G = n or E.
  for (std::uint32_t k = body_begin_[index]; k < body_begin_[index + 1]; ++k) {
    const Front& front = bodies_[k];
    const Scalar w = weight(static_cast<std::size_t>(front.body));
    int row_p = 0;
    for (int p = 0; p < front.count; ++p) {
      const std::uint32_t c_p = members_[front.members + static_cast<std::uint32_t>(p)];
      const Scalar scale_p = w * member_sign_[front.members + static_cast<std::uint32_t>(p)];
      const int rows_p = rows(c_p);
      Scalar n_p[3] = {Scalar(0), Scalar(0), Scalar(0)};
      if (rows_p == 1) {
        const Vector3& d_p = direction(c_p);
        for (int a = 0; a < 3; ++a) n_p[a] = scale_p * d_p(a, 0);
      }
      int row_q = 0;
      for (int q = 0; q <= p; ++q) {
        const std::uint32_t c_q = members_[front.members + static_cast<std::uint32_t>(q)];
        const Scalar sign_q = member_sign_[front.members + static_cast<std::uint32_t>(q)];
        const int rows_q = rows(c_q);
        if (rows_p == 1 && rows_q == 1) {
          const Vector3& d_q = direction(c_q);
          coupling_[entry(front.first, row_p, row_q)] = sign_q * ((n_p[0] * d_q(0, 0) + n_p[1] * d_q(1, 0)) + n_p[2] * d_q(2, 0));
        } else if (rows_p == 1) {  // n_pᵀ·E: row p, columns of q
          for (int b = 0; b < 3; ++b) coupling_[entry(front.first, row_p, row_q + b)] = sign_q * n_p[b];
        } else if (rows_q == 1) {  // E·n_q: rows of p, column q
          const Vector3& d_q = direction(c_q);
          const Scalar scale = scale_p * sign_q;
          for (int a = 0; a < 3; ++a) coupling_[entry(front.first, row_p + a, row_q)] = scale * d_q(a, 0);
        } else {  // E·E, lower triangle when q = p
          for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3 && row_q + b <= row_p + a; ++b) coupling_[entry(front.first, row_p + a, row_q + b)] = a == b ? scale_p * sign_q : Scalar(0);
          }
        }
        row_q += rows_q;
      }
      row_p += rows_p;
    }
  }
  // The constraints, leaves first: each pivot block D = α̃ + its block in the front below
  // (final) and above (updated by its earlier siblings); then the rest of the front above loses
  // its columns.
  bool definite = true;
  const TreeOrdering::Component& range = components_[index];
  for (std::uint32_t k = range.begin; k < range.end; ++k) {
    const Step& step = steps_[k];
    if (step.rows == 1) {
      eliminate<1>(step, compliance(step.constraint), definite);
    } else {
      eliminate<3>(step, compliance(step.constraint), definite);
    }
  }
  return definite;
}

template <typename Scalar>
template <int Rows>
void ConstraintElimination<Scalar>::eliminate(const Step& step, Scalar compliance, bool& definite) {
  Block<Scalar, Rows, Rows> pivot;
  for (int a = 0; a < Rows; ++a) {
    for (int b = 0; b <= a; ++b) {
      Scalar value = a == b ? compliance : Scalar(0);
      value += coupling_[entry(step.below_front, step.below_size - Rows + a, step.below_size - Rows + b)];
      if (step.size > 0) value += coupling_[entry(step.above_front, step.place + a, step.place + b)];
      pivot(a, b) = pivot(b, a) = value;
    }
  }
  const Block<Scalar, Rows, Rows> inverse = positive_definite_inverse<Rows, Scalar>(pivot, definite);
  Scalar* stored = &inverse_pivot_[pivot_begin_[step.constraint]];
  for (int a = 0; a < Rows; ++a) {
    for (int b = 0; b < Rows; ++b) stored[a * Rows + b] = inverse(a, b);
  }
  // The rows after the constraint's in the front above: L_i = F_ic·D⁻¹ (from the unscaled
  // F_ic), F_ij −= L_i·F_jc (unscaled F_jc), then F_ic ← L_i.
  const int rest = step.place + Rows;
  Scalar scaled[kMaxFrontRows][Rows];
  for (int i = rest; i < step.size; ++i) {
    for (int b = 0; b < Rows; ++b) {
      scaled[i][b] = Scalar(0);
      for (int a = 0; a < Rows; ++a) scaled[i][b] += coupling_[entry(step.above_front, i, step.place + a)] * inverse(a, b);
    }
    for (int j = rest; j <= i; ++j) {
      Scalar update = scaled[i][0] * coupling_[entry(step.above_front, j, step.place)];
      for (int b = 1; b < Rows; ++b) update += scaled[i][b] * coupling_[entry(step.above_front, j, step.place + b)];
      coupling_[entry(step.above_front, i, j)] -= update;
    }
  }
  for (int i = rest; i < step.size; ++i) {
    for (int b = 0; b < Rows; ++b) coupling_[entry(step.above_front, i, step.place + b)] = scaled[i][b];
  }
}

}  // namespace limber
