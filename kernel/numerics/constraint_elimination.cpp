#include "limber/kernel/numerics/constraint_elimination.hpp"

#include <stdexcept>

namespace limber {

template <typename Scalar>
void ConstraintElimination<Scalar>::assign(const TreeOrdering& ordering, std::size_t body_count, std::span<const std::int32_t> body_i,
                                           std::span<const std::int32_t> body_j) {
  if (body_i.size() != body_j.size() || ordering.parent.size() != body_count + body_i.size()) {
    throw std::invalid_argument("ConstraintElimination::assign: the ordering is not over these bodies and constraints");
  }
  body_count_ = static_cast<std::int32_t>(body_count);
  const std::size_t constraints = body_i.size();
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
  // The fronts' storage, each body's once; a body with more than kMaxFront constraints leaves
  // its component unsolvable (and stores nothing).
  std::vector<Front> front_of(body_count);
  members_.clear(), member_sign_.clear();
  std::uint32_t entries = 0;
  for (std::size_t body = 0; body < body_count; ++body) {
    const std::size_t size = fronts[body].size();
    front_of[body].body = static_cast<std::uint32_t>(body);
    if (size > static_cast<std::size_t>(kMaxFront)) continue;
    front_of[body] = {static_cast<std::uint32_t>(body), entries, static_cast<std::uint32_t>(members_.size()), static_cast<std::uint8_t>(size)};
    for (const std::uint32_t c : fronts[body]) {
      members_.push_back(c);
      member_sign_.push_back(body_i[c] == static_cast<std::int32_t>(body) ? Scalar(1) : Scalar(-1));
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
        const Front& front = front_of[static_cast<std::size_t>(node)];
        if (fronts[static_cast<std::size_t>(node)].size() > static_cast<std::size_t>(kMaxFront)) solvable_[index] = 0;
        bodies_.push_back(front);
        continue;
      }
      const auto c = static_cast<std::uint32_t>(node - body_count_);
      const std::int32_t up = above[c];
      const std::int32_t below = body_i[c] == up ? body_j[c] : body_i[c];
      const Front& under = front_of[static_cast<std::size_t>(below)];
      Step step;
      step.constraint = c;
      step.below_pivot = under.size > 0 ? static_cast<std::uint32_t>(entry(under.first, under.size - 1, under.size - 1)) : 0;
      if (up >= 0) {
        const Front& over = front_of[static_cast<std::size_t>(up)];
        step.above_front = over.first, step.above_members = over.members, step.size = over.size;
        for (std::uint8_t place = 0; place < over.size; ++place) {
          if (members_[over.members + place] == c) step.place = place;
        }
      }
      steps_.push_back(step);
    }
    range.end = static_cast<std::uint32_t>(steps_.size());
    components_.push_back(range);
    body_begin_.push_back(static_cast<std::uint32_t>(bodies_.size()));
  }
  coupling_.assign(entries, Scalar(0));
  inverse_pivot_.assign(constraints, Scalar(0));
  work_.assign(constraints, Scalar(0));
}

template <typename Scalar>
void ConstraintElimination<Scalar>::solve(std::size_t index) {
  const TreeOrdering::Component& range = components_[index];
  // Forward, leaves first: the rest of a constraint's front above takes L·y.
  for (std::uint32_t k = range.begin; k < range.end; ++k) {
    const Step& step = steps_[k];
    const Scalar y = work_[step.constraint];
    for (int row = step.place + 1; row < step.size; ++row) {
      work_[members_[step.above_members + static_cast<std::uint32_t>(row)]] -= coupling_[entry(step.above_front, row, step.place)] * y;
    }
  }
  // Back, root first: μ_c = y_c/D_c − Σ L·μ over the rest of its front above.
  for (std::uint32_t k = range.end; k-- > range.begin;) {
    const Step& step = steps_[k];
    Scalar mu = work_[step.constraint] * inverse_pivot_[step.constraint];
    for (int row = step.place + 1; row < step.size; ++row) {
      mu -= coupling_[entry(step.above_front, row, step.place)] * work_[members_[step.above_members + static_cast<std::uint32_t>(row)]];
    }
    work_[step.constraint] = mu;
  }
}

template class ConstraintElimination<float>;
template class ConstraintElimination<double>;

}  // namespace limber
