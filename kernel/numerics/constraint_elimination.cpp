#include "limber/kernel/numerics/constraint_elimination.hpp"

#include <stdexcept>

#include <xsimd/xsimd.hpp>

namespace limber {

template <typename Scalar>
void ConstraintElimination<Scalar>::assign(const TreeOrdering& ordering, std::size_t body_count, std::span<const std::int32_t> body_i,
                                           std::span<const std::int32_t> body_j, std::span<const std::uint8_t> rows) {
  if (body_i.size() != body_j.size() || rows.size() != body_i.size() || ordering.parent.size() != body_count + body_i.size()) {
    throw std::invalid_argument("ConstraintElimination::assign: the ordering is not over these bodies and constraints");
  }
  body_count_ = static_cast<std::int32_t>(body_count);
  const std::size_t constraints = body_i.size();
  row_begin_.assign(constraints + 1, 0), pivot_begin_.assign(constraints, 0);
  std::uint32_t pivots = 0;
  for (std::size_t c = 0; c < constraints; ++c) {
    if (rows[c] != 1 && rows[c] != 3) throw std::invalid_argument("ConstraintElimination::assign: a constraint has 1 or 3 rows");
    row_begin_[c + 1] = row_begin_[c] + rows[c];
    pivot_begin_[c] = pivots, pivots += static_cast<std::uint32_t>(rows[c] * rows[c]);
  }
  // A front's members in eliminated order: the constraints below its body as they come in
  // `order`, then the one above it.
  std::vector<std::vector<std::uint32_t>> fronts(body_count);
  std::vector<std::int32_t> above(constraints, -1);
  for (const std::int32_t node : ordering.order) {
    if (node < body_count_) continue;
    const auto c = static_cast<std::size_t>(node - body_count_);
    above[c] = ordering.parent[static_cast<std::size_t>(node)];
    if (above[c] >= 0) fronts[static_cast<std::size_t>(above[c])].push_back(static_cast<std::uint32_t>(c));
  }
  for (std::size_t body = 0; body < body_count; ++body) {
    const std::int32_t up = ordering.parent[body];
    if (up >= 0) fronts[body].push_back(static_cast<std::uint32_t>(up - body_count_));
  }
  // The fronts' storage, each body's once; a body of more than kMaxFrontRows rows leaves its
  // component unsolvable (and stores nothing).
  std::vector<Front> front_of(body_count);
  std::vector<std::uint8_t> small(body_count, 1);
  members_.clear(), member_sign_.clear(), front_row_.clear();
  std::uint32_t entries = 0;
  for (std::size_t body = 0; body < body_count; ++body) {
    std::size_t size = 0;
    for (const std::uint32_t c : fronts[body]) size += rows[c];
    front_of[body].body = static_cast<std::uint32_t>(body);
    if (size > static_cast<std::size_t>(kMaxFrontRows)) {
      small[body] = 0;
      continue;
    }
    front_of[body] = {static_cast<std::uint32_t>(body), entries, static_cast<std::uint32_t>(members_.size()),
                      static_cast<std::uint32_t>(front_row_.size()), static_cast<std::uint8_t>(fronts[body].size()), static_cast<std::uint8_t>(size)};
    for (const std::uint32_t c : fronts[body]) {
      members_.push_back(c);
      member_sign_.push_back(body_i[c] == static_cast<std::int32_t>(body) ? Scalar(1) : Scalar(-1));
      for (std::uint32_t r = row_begin_[c]; r < row_begin_[c + 1]; ++r) front_row_.push_back(r);
    }
    entries += static_cast<std::uint32_t>(size * (size + 1) / 2);
  }
  // Per component: its bodies' fronts and its constraints' steps, in eliminated order.
  components_.clear(), body_begin_.assign(1, 0), steps_.clear(), bodies_.clear();
  solvable_.assign(ordering.components.size(), 1);
  for (std::size_t index = 0; index < ordering.components.size(); ++index) {
    const TreeOrdering::Component& component = ordering.components[index];
    TreeOrdering::Component range{static_cast<std::uint32_t>(steps_.size()), 0, component.body};
    for (std::uint32_t k = component.begin; k < component.end; ++k) {
      const std::int32_t node = ordering.order[k];
      if (node < body_count_) {
        if (!small[static_cast<std::size_t>(node)]) solvable_[index] = 0;
        bodies_.push_back(front_of[static_cast<std::size_t>(node)]);
        continue;
      }
      const auto c = static_cast<std::uint32_t>(node - body_count_);
      const std::int32_t up = above[c];
      const std::int32_t below = body_i[c] == up ? body_j[c] : body_i[c];
      const Front& under = front_of[static_cast<std::size_t>(below)];
      Step step;
      step.constraint = c, step.rows = rows[c];
      step.below_front = under.first, step.below_size = under.size;
      if (up >= 0) {
        const Front& over = front_of[static_cast<std::size_t>(up)];
        step.above_front = over.first, step.above_rows = over.rows_begin, step.size = over.size;
        int row = 0;
        for (std::uint8_t member = 0; member < over.count; ++member) {
          if (members_[over.members + member] == c) step.place = static_cast<std::uint8_t>(row);
          row += rows[members_[over.members + member]];
        }
      }
      steps_.push_back(step);
    }
    range.end = static_cast<std::uint32_t>(steps_.size());
    components_.push_back(range);
    body_begin_.push_back(static_cast<std::uint32_t>(bodies_.size()));
  }
  coupling_.assign(entries, Scalar(0));
  inverse_pivot_.assign(pivots, Scalar(0));
  work_.assign(row_begin_.back(), Scalar(0));
}

// Forward, leaves first: the rest of a constraint's front above takes L·y.
template <typename Scalar>
template <int Rows>
void ConstraintElimination<Scalar>::substitute_forward(const Step& step) {
  const Scalar* y = &work_[row_begin_[step.constraint]];
  for (int i = step.place + Rows; i < step.size; ++i) {
    Scalar change = coupling_[entry(step.above_front, i, step.place)] * y[0];
    for (int a = 1; a < Rows; ++a) change += coupling_[entry(step.above_front, i, step.place + a)] * y[a];
    work_[front_row_[step.above_rows + static_cast<std::uint32_t>(i)]] -= change;
  }
}

// Back, root first: μ_c = D⁻¹·y_c − Lᵀ·μ over the rest of its front above.
template <typename Scalar>
template <int Rows>
void ConstraintElimination<Scalar>::substitute_back(const Step& step) {
  Scalar* y = &work_[row_begin_[step.constraint]];
  const Scalar* inverse = &inverse_pivot_[pivot_begin_[step.constraint]];
  Scalar mu[Rows];
  for (int a = 0; a < Rows; ++a) {
    mu[a] = inverse[a * Rows] * y[0];
    for (int b = 1; b < Rows; ++b) mu[a] += inverse[a * Rows + b] * y[b];
  }
  for (int i = step.place + Rows; i < step.size; ++i) {
    const Scalar above = work_[front_row_[step.above_rows + static_cast<std::uint32_t>(i)]];
    for (int a = 0; a < Rows; ++a) mu[a] -= coupling_[entry(step.above_front, i, step.place + a)] * above;
  }
  for (int a = 0; a < Rows; ++a) y[a] = mu[a];
}

template <typename Scalar>
void ConstraintElimination<Scalar>::solve(std::size_t index) {
  const TreeOrdering::Component& range = components_[index];
  for (std::uint32_t k = range.begin; k < range.end; ++k) {
    if (steps_[k].rows == 1) {
      substitute_forward<1>(steps_[k]);
    } else {
      substitute_forward<3>(steps_[k]);
    }
  }
  for (std::uint32_t k = range.end; k-- > range.begin;) {
    if (steps_[k].rows == 1) {
      substitute_back<1>(steps_[k]);
    } else {
      substitute_back<3>(steps_[k]);
    }
  }
}

template <typename Scalar>
std::size_t ConstraintElimination<Scalar>::storage_bytes() const {
  const auto bytes = [](const auto& array) { return array.size() * sizeof(array[0]); };
  return bytes(components_) + bytes(body_begin_) + bytes(steps_) + bytes(bodies_) + bytes(members_) + bytes(member_sign_) +
         bytes(front_row_) + bytes(row_begin_) + bytes(pivot_begin_) + bytes(coupling_) + bytes(inverse_pivot_) + bytes(work_);
}

template class ConstraintElimination<float>;
template class ConstraintElimination<double>;
template class ConstraintElimination<xsimd::batch<float>>;
template class ConstraintElimination<xsimd::batch<double>>;

}  // namespace limber
