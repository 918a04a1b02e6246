// Baraff's linear-time solve of a constrained system whose bodies and constraints form a tree:
// D. Baraff, "Linear-time dynamics using Lagrange multipliers", SIGGRAPH 1996 (§5–7).
//
// The system, one block row per node (bodies first, then constraints):
//   [ M   Jᵀ ] [x]   [f]
//   [ J  −A  ] [μ] = [c]
// M is block diagonal (each body's symmetric positive definite block of BodySize × BodySize),
// J holds each constraint's blocks on its one or two bodies (rows × BodySize, rows ≤ BodySize),
// and A is block diagonal, each constraint's compliance (0 for a rigid constraint; positive
// semidefinite). Seen as a graph whose nodes are bodies and constraints, with an edge wherever a
// J block is non-zero, the matrix is a tree when the constraints close no loop; eliminating it
// leaves first (children before their parent) then creates no fill, so factor and solve cost
// O(nodes), each node's work on fixed-size blocks.
//
// The two users, one elimination:
// - the Lagrange method (kernel/lagrange/multipliers.cpp): rigid bodies (BodySize 6: mass and
//   world inertia), joints of 1–6 rows, A = 0; x the accelerations, μ = −λ the joint forces;
// - the Verlet family's direct projection (kernel/relaxation/direct_projection.hpp): particles
//   (BodySize 3, M = m·I), distance constraints of one row and zero-length joints of three, A
//   the compliance α̃ = α/Δt² (XPBD); x the position change, μ = −Δλ.
//
// Values are numbers (double, float) or SIMD lanes of numbers (xsimd::batch): with lanes, each
// lane is its own system of the same shape (same ordering, same rows per constraint: instances
// of one skeleton side by side), and lane k gives the bits a number-valued elimination gives on
// lane k's system (lane_blocks.hpp). The block products are written as loops for that reason.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/numerics/lane_blocks.hpp"
#include "limber/kernel/numerics/small_cholesky.hpp"

namespace limber {

/// Calls function(std::integral_constant<int, rows>{}) for rows in 1…MaxRows, so a constraint's
/// blocks get fixed-size (unrolled, vectorized) arithmetic.
template <int MaxRows, typename Function>
void with_rows(int rows, Function&& function) {
  static_assert(MaxRows >= 1 && MaxRows <= 6);
  if constexpr (MaxRows >= 2) if (rows == 1) return function(std::integral_constant<int, 1>{});
  if constexpr (MaxRows >= 3) if (rows == 2) return function(std::integral_constant<int, 2>{});
  if constexpr (MaxRows >= 4) if (rows == 3) return function(std::integral_constant<int, 3>{});
  if constexpr (MaxRows >= 5) if (rows == 4) return function(std::integral_constant<int, 4>{});
  if constexpr (MaxRows >= 6) if (rows == 5) return function(std::integral_constant<int, 5>{});
  return function(std::integral_constant<int, MaxRows>{});
}

/// The elimination order of a body–constraint graph (order_tree()).
struct TreeOrdering {
  /// Nodes: bodies 0…body_count−1, then constraint c as node body_count + c.
  std::vector<std::int32_t> parent;  ///< per node, −1 for a root (and for loop-closing constraints)
  std::vector<std::int32_t> order;   ///< tree nodes, every node before its parent
  /// Each connected component's nodes are order[begin, end); `body` is one of its bodies.
  struct Component {
    std::uint32_t begin = 0, end = 0;
    std::int32_t body = 0;
  };
  std::vector<Component> components;
  /// Constraints left out of the tree because they close a loop (between bodies already joined,
  /// or a second constraint to the world in one component), in the order they were found:
  /// first those between bodies by index, then the world ones.
  std::vector<std::uint32_t> loop_constraints;
};

/// Orders the tree of `body_count` bodies and the constraints c joining inboard[c] and
/// outboard[c] (inboard[c] < 0: to the world, which is not a node; outboard[c] < 0 as well: a
/// constraint that joins no body, left out) for elimination. A constraint
/// to the world has no body below it to be eliminated into, so it must be its component's root:
/// each component is rooted at its first constraint to the world, else at its lowest body, and
/// ordered breadth-first from there (reversed, so children come first). Loop-closing
/// constraints are reported, not ordered. O(nodes).
TreeOrdering order_tree(std::size_t body_count, std::span<const std::int32_t> inboard, std::span<const std::int32_t> outboard);

/// Factor-and-solve storage and arithmetic for a TreeOrdering. Value: a floating-point type, or
/// a SIMD batch of one (one system per lane). Allocates only in assign().
template <typename Value, int BodySize>
class TreeElimination {
 public:
  using BodyMatrix = Block<Value, BodySize, BodySize>;
  using BodyVector = Block<Value, BodySize, 1>;

  /// Takes the ordering and each constraint's row count (1…BodySize).
  void assign(TreeOrdering ordering, std::size_t body_count, std::vector<std::uint8_t> constraint_rows) {
    ordering_ = std::move(ordering);
    body_count_ = static_cast<std::int32_t>(body_count);
    position_.assign(ordering_.parent.size(), 0);
    for (std::size_t k = 0; k < ordering_.order.size(); ++k) position_[static_cast<std::size_t>(ordering_.order[k])] = static_cast<std::uint32_t>(k);
    rows_ = std::move(constraint_rows);
    const std::size_t nodes = ordering_.parent.size();
    diagonal_.assign(nodes, BodyMatrix::Zero());
    to_parent_.assign(nodes, BodyMatrix::Zero());
    work_.assign(nodes, BodyVector::Zero());
    inverse_.assign(nodes, BodyMatrix::Zero());
    if constexpr (!kInvertBodies) body_factor_.resize(body_count);
  }

  const TreeOrdering& ordering() const { return ordering_; }
  std::size_t node_count() const { return ordering_.parent.size(); }
  std::int32_t body_count() const { return body_count_; }
  int rows(std::size_t constraint) const { return rows_[constraint]; }

  /// Inputs, set before eliminate() for every node of the components solved: a body's block of M
  /// (its lower triangle is read), a constraint's −A in the top-left rows × rows corner (zero for
  /// rigid); and work(node) = the right-hand side (f for a body, c in a constraint's top rows).
  /// Outputs, after it: work(body) = x, work(constraint) top rows = μ.
  BodyMatrix& diagonal(std::size_t node) { return diagonal_[node]; }
  BodyVector& work(std::size_t node) { return work_[node]; }
  const BodyVector& work(std::size_t node) const { return work_[node]; }

  /// Factors and solves the nodes order[begin, end) (whole components): factor() then solve().
  /// edge(constraint, body) returns the constraint's J block on that body (BodySize × BodySize,
  /// a BodyMatrix or any block read by (i, j)), of which the top rows(constraint) rows are read.
  /// Returns false when a body's block is not positive definite in some lane (that lane's
  /// solution is then meaningless).
  template <typename Edge>
  bool eliminate(std::uint32_t begin, std::uint32_t end, Edge&& edge) {
    const bool definite = factor(begin, end, std::forward<Edge>(edge));
    solve(begin, end);
    return definite;
  }

  /// Factors the nodes order[begin, end), children first: L = H_{parent,node}·D⁻¹, then
  /// D_parent −= L·H_{node,parent}. The diagonal inputs are consumed; the work vectors are not
  /// read. Returns false as eliminate() does.
  template <typename Edge>
  bool factor(std::uint32_t begin, std::uint32_t end, Edge&& edge) {
    bool definite = true;
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::int32_t node = ordering_.order[k];
      if (node < body_count_) {
        factor_body(node, edge, definite);
      } else {
        factor_constraint(node, edge);
      }
    }
    return definite;
  }

  /// Solves the factored nodes order[begin, end) for the right-hand sides in work(): forward,
  /// children first, y_parent −= L·y_node; back, parents first, x_node = D⁻¹·y_node − Lᵀ·x_parent.
  /// A factor serves any number of solves (a chord iteration: new right-hand sides, one matrix).
  void solve(std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t k = begin; k < end; ++k) forward_substitute(ordering_.order[k]);
    for (std::uint32_t k = end; k-- > begin;) back_substitute(ordering_.order[k]);
  }

  /// solve() for a right-hand side that is zero outside `nodes`: nodes of factored components,
  /// each one's parent listed too (unless a root), children first (path_to_root gives such a
  /// list). Reads and writes work() of those nodes only, and gives there what solve() gives:
  /// the rest of the tree adds nothing to them. O(the nodes listed): one load's response at a
  /// few bodies costs the depth of the tree, not its size.
  void solve_nodes(std::span<const std::int32_t> nodes) {
    for (const std::int32_t node : nodes) forward_substitute(node);
    for (std::size_t k = nodes.size(); k-- > 0;) back_substitute(nodes[k]);
  }

  /// The nodes on the paths from each of `from` (tree nodes of one component) up to its root,
  /// each once, children first, into the front of `out` (room for the component's nodes);
  /// returns their count: solve_nodes' list for loads at `from`.
  std::size_t path_to_root(std::span<const std::int32_t> from, std::span<std::int32_t> out) const {
    const auto before = [&](std::int32_t a, std::int32_t b) { return position_[a] < position_[b]; };
    std::size_t count = 0;
    for (const std::int32_t source : from) {
      // Up from the source until the paths already listed (sorted: a binary search) are met.
      const auto listed = out.begin() + static_cast<std::ptrdiff_t>(count);
      for (std::int32_t node = source; node >= 0; node = ordering_.parent[node]) {
        const auto found = std::lower_bound(out.begin(), listed, node, before);
        if (found != listed && *found == node) break;
        out[count++] = node;
      }
      std::sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(count), before);
    }
    return count;
  }

  /// After factor() of the nodes order[begin, end) (whole components): each body's diagonal
  /// block of H⁻¹ into mobility(body), parents first by Takahashi's recursion on the factor
  /// H = L·D·Lᵀ (Takahashi, Fagan & Chen 1973; on a tree no other block is needed):
  ///   Z_root = D_root⁻¹,   Z_node = D_node⁻¹ + L_{parent,node}ᵀ·Z_parent·L_{parent,node}.
  /// A body's block is its mobility in the constrained system, M⁻¹ − M⁻¹Jᵀ(J M⁻¹ Jᵀ + A)⁻¹J M⁻¹
  /// restricted to that body: the motion x = Z·f its load f alone makes with every constraint
  /// kept (an articulated body's inverse inertia, seen from that body). O(nodes), about the work
  /// of a factor. A constraint's block, Z over its μ, is kept in the scratch only.
  void inverse_diagonal(std::uint32_t begin, std::uint32_t end) {
    const auto& order = ordering_.order;
    const auto& parent_of = ordering_.parent;
    for (std::uint32_t k = end; k-- > begin;) {
      const std::int32_t node = order[k], parent = parent_of[node];
      BodyMatrix& z = inverse_[node];
      if (node < body_count_) {
        z = body_inverse(node);
        if (parent < 0) continue;
        with_rows<BodySize>(rows_[parent - body_count_], [&](auto rows) {
          constexpr int m = decltype(rows)::value;
          add_congruent<m, BodySize>(z, to_parent_[node], inverse_[parent]);
        });
        continue;
      }
      with_rows<BodySize>(rows_[node - body_count_], [&](auto rows) {
        constexpr int m = decltype(rows)::value;
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < m; ++j) z(i, j) = diagonal_[node](i, j);
        }
        if (parent < 0) return;
        add_congruent<BodySize, m>(z, to_parent_[node], inverse_[parent]);
      });
    }
  }

  /// A body's block of H⁻¹ (inverse_diagonal()), BodySize × BodySize.
  const BodyMatrix& mobility(std::size_t body) const { return inverse_[body]; }

 private:
  static constexpr bool kInvertBodies = BodySize <= 3;

  // z (cols × cols) += Lᵀ·Z_p·L: L the top-left rows × cols of l, Z_p of parent rows × rows.
  template <int rows, int cols>
  static void add_congruent(BodyMatrix& z, const BodyMatrix& l, const BodyMatrix& parent) {
    Block<Value, rows, cols> product;  // Z_p·L
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < cols; ++j) product(i, j) = dot<rows>([&](int c) { return parent(i, c) * l(c, j); });
    }
    for (int i = 0; i < cols; ++i) {
      for (int j = 0; j < cols; ++j) z(i, j) += dot<rows>([&](int c) { return l(c, i) * product(c, j); });
    }
  }

  // D⁻¹ of a factored body.
  BodyMatrix body_inverse(std::int32_t node) const {
    if constexpr (kInvertBodies) {
      return diagonal_[node];
    } else {
      BodyMatrix identity = BodyMatrix::Zero();
      for (int i = 0; i < BodySize; ++i) identity(i, i) = Value(1);
      body_factor_[node].solve_in_place(identity);
      return identity;
    }
  }

  /// Σ_{c<n} term(c), summed in order.
  template <int n, typename Term>
  static Value dot(Term&& term) {
    Value sum = term(0);
    for (int c = 1; c < n; ++c) sum += term(c);
    return sum;
  }

  // A body: D⁻¹ (in place, or its Cholesky factor), then into its parent constraint's D:
  // L = B·D⁻¹ (top m rows), D_parent −= L·Bᵀ, B = H_{constraint,body}.
  template <typename Edge>
  void factor_body(std::int32_t node, Edge& edge, bool& definite) {
    BodyMatrix& block_d = diagonal_[node];
    if constexpr (kInvertBodies) {
      block_d = positive_definite_inverse<BodySize, Value>(block_d, definite);
    } else {
      definite = body_factor_[node].compute(block_d) && definite;
    }
    const std::int32_t parent = ordering_.parent[node];
    if (parent < 0) return;
    const auto& block = edge(static_cast<std::size_t>(parent - body_count_), node);
    BodyMatrix& l = to_parent_[node];
    with_rows<BodySize>(rows_[parent - body_count_], [&](auto rows) {
      constexpr int m = decltype(rows)::value;
      if constexpr (kInvertBodies) {
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < BodySize; ++j) l(i, j) = dot<BodySize>([&](int c) { return block(i, c) * block_d(c, j); });
        }
      } else {
        Block<Value, BodySize, m> transposed;  // D⁻¹·Bᵀ = (B·D⁻¹)ᵀ, D symmetric
        for (int i = 0; i < BodySize; ++i) {
          for (int j = 0; j < m; ++j) transposed(i, j) = block(j, i);
        }
        body_factor_[node].solve_in_place(transposed);
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < BodySize; ++j) l(i, j) = transposed(j, i);
        }
      }
      BodyMatrix& up = diagonal_[parent];
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) up(i, j) -= dot<BodySize>([&](int c) { return l(i, c) * block(j, c); });
      }
    });
  }

  // A constraint: D is negative definite (−A minus the Schur complement J M⁻¹ Jᵀ of its
  // children), D⁻¹ = −(−D)⁻¹ in place; then into its parent body's D: L = Bᵀ·D⁻¹ (left m
  // columns), D_parent −= L·B, B = H_{constraint,parent}.
  template <typename Edge>
  void factor_constraint(std::int32_t node, Edge& edge) {
    const auto constraint = static_cast<std::size_t>(node - body_count_);
    const std::int32_t parent = ordering_.parent[node];
    BodyMatrix& block_d = diagonal_[node];
    with_rows<BodySize>(rows_[constraint], [&](auto rows) {
      constexpr int m = decltype(rows)::value;
      Block<Value, m, m> negative;
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) negative(i, j) = -block_d(i, j);
      }
      bool constraint_definite = true;  // −D is positive definite by construction
      const Block<Value, m, m> inverse = positive_definite_inverse<m, Value>(negative, constraint_definite);
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) block_d(i, j) = -inverse(i, j);
      }
      if (parent < 0) return;
      const auto& block = edge(constraint, parent);
      BodyMatrix& l = to_parent_[node];
      for (int i = 0; i < BodySize; ++i) {
        for (int j = 0; j < m; ++j) l(i, j) = dot<m>([&](int c) { return block(c, i) * block_d(c, j); });
      }
      BodyMatrix& up = diagonal_[parent];
      for (int i = 0; i < BodySize; ++i) {
        for (int j = 0; j < BodySize; ++j) up(i, j) -= dot<m>([&](int c) { return l(i, c) * block(c, j); });
      }
    });
  }

  // Forward, children first: y_parent −= L·y_node.
  void forward_substitute(std::int32_t node) {
    const std::int32_t parent = ordering_.parent[node];
    if (parent < 0) return;
    const BodyMatrix& l = to_parent_[node];
    const BodyVector& y = work_[node];
    BodyVector& up = work_[parent];
    if (node < body_count_) {
      with_rows<BodySize>(rows_[parent - body_count_], [&](auto rows) {
        constexpr int m = decltype(rows)::value;
        for (int i = 0; i < m; ++i) up(i, 0) -= dot<BodySize>([&](int c) { return l(i, c) * y(c, 0); });
      });
      return;
    }
    with_rows<BodySize>(rows_[node - body_count_], [&](auto rows) {
      constexpr int m = decltype(rows)::value;
      for (int i = 0; i < BodySize; ++i) up(i, 0) -= dot<m>([&](int c) { return l(i, c) * y(c, 0); });
    });
  }

  // Back, parents first: x_node = D⁻¹·y_node − Lᵀ·x_parent.
  void back_substitute(std::int32_t node) {
    const std::int32_t parent = ordering_.parent[node];
    if (node < body_count_) {
      back_substitute_body(node, parent);
      return;
    }
    with_rows<BodySize>(rows_[node - body_count_], [&](auto rows) {
      constexpr int m = decltype(rows)::value;
      const BodyMatrix& d = diagonal_[node];
      const BodyMatrix& l = to_parent_[node];
      BodyVector& y = work_[node];
      Value x[m];
      for (int i = 0; i < m; ++i) {
        x[i] = dot<m>([&](int c) { return d(i, c) * y(c, 0); });
        if (parent >= 0) x[i] -= dot<BodySize>([&](int c) { return l(c, i) * work_[parent](c, 0); });
      }
      for (int i = 0; i < m; ++i) y(i, 0) = x[i];
    });
  }

  // x_body = D⁻¹·y − Lᵀ·x_parent (L: the top m rows).
  void back_substitute_body(std::int32_t node, std::int32_t parent) {
    BodyVector& y = work_[node];
    BodyVector x;
    if constexpr (kInvertBodies) {
      const BodyMatrix& d = diagonal_[node];
      for (int i = 0; i < BodySize; ++i) x(i, 0) = dot<BodySize>([&](int c) { return d(i, c) * y(c, 0); });
    } else {
      x = y;
      body_factor_[node].solve_in_place(x);
    }
    if (parent >= 0) {
      const BodyMatrix& l = to_parent_[node];
      const BodyVector& up = work_[parent];
      with_rows<BodySize>(rows_[parent - body_count_], [&](auto rows) {
        constexpr int m = decltype(rows)::value;
        for (int i = 0; i < BodySize; ++i) x(i, 0) -= dot<m>([&](int c) { return l(c, i) * up(c, 0); });
      });
    }
    y = x;
  }

  TreeOrdering ordering_;
  std::vector<std::uint32_t> position_;  // per tree node: its place in ordering_.order
  std::int32_t body_count_ = 0;
  std::vector<std::uint8_t> rows_;
  /// Per node: D (inverted in place when it is eliminated, except a body's of more than 3 rows,
  /// whose Cholesky factor body_factor_ keeps) and L = H_{parent,node}·D⁻¹ (top rows for a body,
  /// left columns for a constraint).
  std::vector<BodyMatrix> diagonal_, to_parent_;
  std::vector<BodyVector> work_;
  std::vector<BodyMatrix> inverse_;  // inverse_diagonal()'s Z blocks, per node
  std::vector<SmallCholesky<BodySize, Value>> body_factor_;
};

}  // namespace limber
