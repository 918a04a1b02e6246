#include "limber/kernel/relaxation/direct_projection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "limber/kernel/relaxation/distance_projection.hpp"

namespace limber {
namespace {

template <typename Scalar>
using Vector3s = Eigen::Matrix<Scalar, 3, 1>;

// The weight a particle's correction gets: its inverse mass (weighted rule, eq. 4.7), or 1 for
// every movable particle (unweighted rule, eq. 4.6).
template <typename Scalar>
Scalar correction_weight(const VerletState<Scalar>& state, std::uint32_t particle) {
  const Scalar w = state.particles.inverse_mass[particle];
  return state.options.rule == RelaxationRule::weighted || w == Scalar(0) ? w : Scalar(1);
}

// A constraint of one row (distance) or three (zero-length joint).
template <typename Scalar>
bool is_point_constraint(const VerletState<Scalar>& state, std::size_t c) {
  return state.constraints.rest_length[c] == Scalar(0);
}

// Moves the constraint's two particles by W·Jᵀ·impulse (impulse in its rows; `direction` is n
// of a distance constraint).
template <typename Scalar>
void apply_impulse(VerletState<Scalar>& state, std::size_t c, const Vector3s<Scalar>& impulse, const Vector3s<Scalar>& direction) {
  const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
  const Vector3s<Scalar> along = is_point_constraint(state, c) ? impulse : Vector3s<Scalar>(direction * impulse.x());
  auto& particles = state.particles;
  particles.set_position(i, particles.position(i) + correction_weight(state, i) * along);
  particles.set_position(j, particles.position(j) - correction_weight(state, j) * along);
}

// n = (x_i − x_j)/|x_i − x_j| and C = |x_i − x_j| − d for a distance constraint, C = x_i − x_j for
// a zero-length joint (first row, or all three).
template <typename Scalar>
Vector3s<Scalar> constraint_value(const VerletState<Scalar>& state, std::size_t c, Vector3s<Scalar>& direction) {
  const auto& particles = state.particles;
  const Vector3s<Scalar> separation = particles.position(state.constraints.particle_i[c]) - particles.position(state.constraints.particle_j[c]);
  if (is_point_constraint(state, c)) return separation;
  const Scalar length = separation.norm();
  // Coincident ends have no direction: keep the last one (any unit vector gives a valid row).
  if (length > Scalar(0)) direction = separation / length;
  return Vector3s<Scalar>(length - state.constraints.rest_length[c], 0, 0);
}

template <typename Scalar>
std::uint32_t island_of_particle(const VerletState<Scalar>& state, std::uint32_t particle) {
  const auto it = std::upper_bound(state.islands.begin(), state.islands.end(), particle,
                                   [](std::uint32_t p, const Island& island) { return p < island.particle_end; });
  return static_cast<std::uint32_t>(it - state.islands.begin());
}

// The direction a distance constraint's rows use in this Newton step: its start gradient under
// the rattle rule (SHAKE's linearization, fixed for the substep) while the current direction n
// stays within kStartGradientMinimumCosine of it, else — the pbd fallback, counted once a
// substep — n itself.
template <typename Scalar>
const Vector3s<Scalar>& linearization(VerletState<Scalar>& state, std::size_t c) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  if (!uses_rattle(state)) return direct.direction[c];
  Vector3s<Scalar>& start = state.plan.constraint_gradient[c];
  if (start.squaredNorm() > Scalar(0) && !(direct.direction[c].dot(start) > Scalar(kStartGradientMinimumCosine))) {
    start.setZero();
    state.plan.fallbacks.value.fetch_add(1, std::memory_order_relaxed);
  }
  return start.squaredNorm() > Scalar(0) ? start : direct.direction[c];
}

}  // namespace

template <typename Scalar>
void prepare_direct_projection(VerletState<Scalar>& state) {
  const VerletOptions& options = state.options;
  if (options.newton_iterations < 1 || options.newton_iterations > kMaxNewtonIterations) {
    throw std::invalid_argument("options: newton_iterations must be in [1, " + std::to_string(kMaxNewtonIterations) + "]");
  }
  if (!(options.compliance >= 0)) throw std::invalid_argument("options: compliance must be a non-negative number of m/N");
  DirectProjection<Scalar>& direct = state.plan.direct;
  const auto& particles = state.particles;
  const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
  direct.body_of_particle.assign(particles.size(), -1);
  direct.particle_of_body.clear();
  direct.body_mass.clear();
  for (std::uint32_t p = 0; p < particles.size(); ++p) {
    if (particles.inverse_mass[p] == Scalar(0)) continue;
    direct.body_of_particle[p] = static_cast<std::int32_t>(direct.particle_of_body.size());
    direct.particle_of_body.push_back(p);
    direct.body_mass.push_back(Scalar(1) / correction_weight(state, p));
  }
  // A constraint at a pinned particle is a constraint to the world (inboard −1).
  std::vector<std::int32_t> inboard(constraints.size()), outboard(constraints.size());
  std::vector<std::uint8_t> rows(constraints.size());
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    std::int32_t a = direct.body_of_particle[constraints.particle_i[c]], b = direct.body_of_particle[constraints.particle_j[c]];
    if (b < 0) std::swap(a, b);
    inboard[c] = a, outboard[c] = b;
    rows[c] = is_point_constraint(state, c) ? 3 : 1;
  }
  TreeOrdering ordering = order_tree(direct.particle_of_body.size(), inboard, outboard);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> island_components, island_loops;
  for (std::size_t k = 0; k < ordering.components.size(); ++k) {
    const std::uint32_t particle = direct.particle_of_body[static_cast<std::size_t>(ordering.components[k].body)];
    island_components.emplace_back(island_of_particle(state, particle), static_cast<std::uint32_t>(k));
  }
  for (const std::uint32_t c : ordering.loop_constraints) {
    island_loops.emplace_back(island_of_particle(state, constraints.particle_i[c]), c);
  }
  // Loop-closing constraints in storage order, like a sequential sweep.
  std::sort(island_loops.begin(), island_loops.end());
  direct.island_components = group_by_row(state.islands.size(), island_components);
  direct.island_loop_constraints = group_by_row(state.islands.size(), island_loops);
  std::vector<std::int32_t> body_i(constraints.size()), body_j(constraints.size());
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    body_i[c] = direct.body_of_particle[constraints.particle_i[c]], body_j[c] = direct.body_of_particle[constraints.particle_j[c]];
  }
  direct.constraint_space.assign(ordering, direct.particle_of_body.size(), body_i, body_j, rows);
  direct.in_constraint_space.assign(ordering.components.size(), 0);
  for (std::size_t k = 0; k < ordering.components.size(); ++k) direct.in_constraint_space[k] = direct.constraint_space.solvable(k) ? 1 : 0;
  direct.factored_direction.assign(constraints.size(), Vector3s<Scalar>::Zero());
  direct.factored_compliance.assign(constraints.size(), std::numeric_limits<Scalar>::quiet_NaN());
  direct.correction.assign(direct.particle_of_body.size(), Vector3s<Scalar>::Zero());
  direct.elimination.assign(std::move(ordering), direct.particle_of_body.size(), std::move(rows));
  direct.multiplier.assign(constraints.size(), Vector3s<Scalar>::Zero());
  direct.direction.assign(constraints.size(), Vector3s<Scalar>::UnitX());
  direct.scaled_compliance.assign(constraints.size(), Scalar(0));
  direct.multiplier_time_step = 0;
}

template <typename Scalar>
void begin_direct_projection(VerletState<Scalar>& state, double dt) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  const auto& components = direct.elimination.ordering().components;
  const auto& order = direct.elimination.ordering().order;
  const auto body_count = direct.elimination.body_count();
  // α̃ = α/Δt² (XPBD). Under the rattle rule the position stage carries a force with velocity
  // Verlet's weight Δt²/2, so its compliance is 2α/Δt²: the same static stretch C = α·F.
  const auto compliance = static_cast<Scalar>((uses_rattle(state) ? 2 : 1) * state.options.compliance / (dt * dt));
  const bool warm = state.options.warm_start && direct.multiplier_time_step > 0;
  const auto rescale = static_cast<Scalar>(warm ? (dt / direct.multiplier_time_step) * (dt / direct.multiplier_time_step) : 0.0);
  const auto visit = [&](std::size_t c) {
    direct.scaled_compliance[c] = compliance;
    Vector3s<Scalar>& lambda = direct.multiplier[c];
    lambda *= rescale;
    if (!warm) return;
    constraint_value(state, c, direct.direction[c]);
    apply_impulse(state, c, lambda, is_point_constraint(state, c) ? direct.direction[c] : linearization(state, c));
  };
  for (const std::uint32_t island : state.awake_islands) {
    for (const std::uint32_t k : direct.island_components.row(island)) {
      for (std::uint32_t n = components[k].begin; n < components[k].end; ++n) {
        if (order[n] >= body_count) visit(static_cast<std::size_t>(order[n] - body_count));
      }
    }
    for (const std::uint32_t c : direct.island_loop_constraints.row(island)) direct.multiplier[c].setZero();
  }
  direct.multiplier_time_step = dt;
}

namespace {

// eliminate_awake's work on component k in constraint space: the right-hand sides, a factor
// unless the last one's directions (of its one-row constraints) and compliances are these bits,
// the solve, and each particle's correction W·Jᵀ·Δλ summed over its constraints. Counts the
// constraints into `projected`; returns the largest |Δ|.
template <typename Scalar, typename Prepare, typename Direction, typename Compliance, typename Body, typename Row>
double eliminate_in_constraint_space(VerletState<Scalar>& state, std::uint32_t k, Prepare& prepare, Direction& direction,
                                     Compliance& compliance, Body& body, Row& row, std::uint64_t& projected) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  ConstraintElimination<Scalar>& solver = direct.constraint_space;
  const TreeOrdering& ordering = direct.elimination.ordering();
  const std::int32_t body_count = direct.elimination.body_count();
  const std::uint32_t begin = ordering.components[k].begin, end = ordering.components[k].end;
  bool stale = false;
  for (std::uint32_t n = begin; n < end; ++n) {
    const std::int32_t node = ordering.order[n];
    if (node < body_count) {
      direct.correction[static_cast<std::size_t>(node)].setZero();
      continue;
    }
    const auto c = static_cast<std::size_t>(node - body_count);
    ++projected;
    const Vector3s<Scalar> right = prepare(c);
    const int rows = solver.rows(c);
    for (int r = 0; r < rows; ++r) solver.multiplier(c, r) = right[r];
    const Scalar alpha = compliance(c);
    if (!(alpha == direct.factored_compliance[c])) stale = true, direct.factored_compliance[c] = alpha;
    if (rows == 3) continue;  // J = ±E: no direction
    const Vector3s<Scalar>& n_c = direction(c);
    if (n_c != direct.factored_direction[c]) stale = true, direct.factored_direction[c] = n_c;
  }
  if (stale) {
    solver.factor(
        k, [&](std::size_t b) { return correction_weight(state, direct.particle_of_body[b]); },
        [&](std::size_t c) -> const Vector3s<Scalar>& { return direct.factored_direction[c]; },
        [&](std::size_t c) { return direct.factored_compliance[c]; });
  }
  solver.solve(k);
  const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
  for (std::uint32_t n = begin; n < end; ++n) {
    const std::int32_t node = ordering.order[n];
    if (node < body_count) continue;
    const auto c = static_cast<std::size_t>(node - body_count);
    const bool point = solver.rows(c) == 3;
    const Vector3s<Scalar> lambda = point ? Vector3s<Scalar>(solver.multiplier(c, 0), solver.multiplier(c, 1), solver.multiplier(c, 2))
                                          : Vector3s<Scalar>(solver.multiplier(c), 0, 0);
    const Vector3s<Scalar> along = point ? lambda : Vector3s<Scalar>(direct.factored_direction[c] * lambda.x());
    for (const auto& [particle, sign] : {std::pair{constraints.particle_i[c], Scalar(1)}, std::pair{constraints.particle_j[c], Scalar(-1)}}) {
      const std::int32_t b = direct.body_of_particle[particle];
      if (b >= 0) direct.correction[static_cast<std::size_t>(b)] += (sign * correction_weight(state, particle)) * along;
    }
    row(c, Vector3s<Scalar>(-lambda));  // μ = −Δλ, as the particle blocks give it
  }
  double largest = 0;
  for (std::uint32_t n = begin; n < end; ++n) {
    const std::int32_t node = ordering.order[n];
    if (node >= body_count) continue;
    const Vector3s<Scalar>& delta = direct.correction[static_cast<std::size_t>(node)];
    body(direct.particle_of_body[static_cast<std::size_t>(node)], delta);
    largest = std::max(largest, static_cast<double>(delta.norm()));
  }
  return largest;
}

// Solves one system [M Jᵀ; J −α̃] over the awake islands' trees and hands each body's solution to
// `body(p, Δ)` (the particle's correction) and each constraint's to `row(c, −Δλ)`. `prepare(c)`
// gives a constraint's right-hand side and refreshes the direction `direction(c)` its rows use;
// `compliance(c)` is its α̃. Then `loop(c)` runs on the loop-closing constraints. Returns the
// largest |Δ|.
template <typename Scalar, typename Prepare, typename Direction, typename Compliance, typename Body, typename Row, typename Loop>
double eliminate_awake(VerletState<Scalar>& state, Prepare&& prepare, Direction&& direction, Compliance&& compliance,
                       Body&& body, Row&& row, Loop&& loop) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  TreeElimination<Scalar, 3>& elimination = direct.elimination;
  const auto& components = elimination.ordering().components;
  const auto& order = elimination.ordering().order;
  const auto body_count = elimination.body_count();
  const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  // J's block of constraint c on a body: ±I for a zero-length joint, ±nᵀ (first row) for a
  // distance constraint; + at particle i.
  const auto edge = [&](std::size_t c, std::int32_t node) -> Matrix3 {
    const Scalar sign = direct.body_of_particle[constraints.particle_i[c]] == node ? Scalar(1) : Scalar(-1);
    if (is_point_constraint(state, c)) return sign * Matrix3::Identity();
    Matrix3 block = Matrix3::Zero();
    block.row(0) = sign * direction(c).transpose();
    return block;
  };
  double largest = 0;
  std::uint64_t projected = 0;
  for (const std::uint32_t island : state.awake_islands) {
    for (const std::uint32_t k : direct.island_components.row(island)) {
      const std::uint32_t begin = components[k].begin, end = components[k].end;
      if (direct.in_constraint_space[k]) {
        largest = std::max(largest, eliminate_in_constraint_space(state, k, prepare, direction, compliance, body, row, projected));
        continue;
      }
      // M = 1/w per particle; the right-hand side per constraint, α̃ on its diagonal.
      for (std::uint32_t n = begin; n < end; ++n) {
        const std::int32_t node = order[n];
        if (node < body_count) {
          elimination.diagonal(node) = direct.body_mass[static_cast<std::size_t>(node)] * Matrix3::Identity();
          elimination.work(node).setZero();
          continue;
        }
        const auto c = static_cast<std::size_t>(node - body_count);
        elimination.diagonal(node) = -compliance(c) * Matrix3::Identity();
        elimination.work(node) = prepare(c);
        ++projected;
      }
      elimination.eliminate(begin, end, edge);
      for (std::uint32_t n = begin; n < end; ++n) {
        const std::int32_t node = order[n];
        if (node < body_count) {
          const Vector3s<Scalar>& delta = elimination.work(node);
          body(direct.particle_of_body[static_cast<std::size_t>(node)], delta);
          largest = std::max(largest, static_cast<double>(delta.norm()));
        } else {
          row(static_cast<std::size_t>(node - body_count), elimination.work(node));
        }
      }
    }
    for (const std::uint32_t c : direct.island_loop_constraints.row(island)) {
      largest = std::max(largest, loop(c));
      ++projected;
    }
  }
  state.counters.constraint_projections += projected;
  return largest;
}

}  // namespace

template <typename Scalar>
double direct_projection_step(VerletState<Scalar>& state) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  auto& particles = state.particles;
  const bool rattle = uses_rattle(state);
  std::uint64_t loop_fallbacks = 0;
  const double largest = eliminate_awake(
      state,
      // −C(x) − α̃·λ at the current positions (refreshing n, and the rattle rule's choice of rows).
      // A rigid row linearized at n₀ has the true slope n·n₀ times the one it is solved with:
      // dividing its right-hand side by n·n₀ makes the step exact for a lone constraint (SHAKE's
      // own update), leaving only the couplings between rows to the chord iteration.
      [&](std::size_t c) -> Vector3s<Scalar> {
        const Vector3s<Scalar> value = constraint_value(state, c, direct.direction[c]);
        if (rattle && !is_point_constraint(state, c) && direct.scaled_compliance[c] == Scalar(0)) {
          return -value / direct.direction[c].dot(linearization(state, c));
        }
        return -value - direct.scaled_compliance[c] * direct.multiplier[c];
      },
      [&](std::size_t c) -> const Vector3s<Scalar>& { return linearization(state, c); },
      [&](std::size_t c) { return direct.scaled_compliance[c]; },
      [&](std::uint32_t p, const Vector3s<Scalar>& delta) { particles.set_position(p, particles.position(p) + delta); },
      [&](std::size_t c, const Vector3s<Scalar>& solution) {
        const int rows = direct.elimination.rows(c);
        direct.multiplier[c].head(rows) -= solution.head(rows);  // Δλ = −μ
      },
      [&](std::uint32_t c) {
        return static_cast<double>(rattle ? project_distance_constraint_from_start(particles, state.constraints, c, state.options.rule,
                                                                                   Scalar(1), state.plan.constraint_gradient[c], loop_fallbacks)
                                          : project_distance_constraint(particles, state.constraints, c, state.options.rule));
      });
  state.plan.fallbacks.value += loop_fallbacks;
  return largest;
}

template <typename Scalar>
double direct_velocity_projection(VerletState<Scalar>& state) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  auto& particles = state.particles;
  // Rows at the current positions: n for a distance constraint (as stored by
  // begin_velocity_projection), all three for a zero-length joint; right-hand side −J·v.
  // Coincident ends have no gradient (0): any unit row keeps the system regular.
  const auto direction = [&](std::size_t c) -> const Vector3s<Scalar>& {
    const Vector3s<Scalar>& n = state.plan.constraint_gradient[c];
    return n.squaredNorm() > Scalar(0) ? n : direct.direction[c];
  };
  return eliminate_awake(
      state,
      [&](std::size_t c) -> Vector3s<Scalar> {
        const Vector3s<Scalar> relative =
            particles.velocity(state.constraints.particle_i[c]) - particles.velocity(state.constraints.particle_j[c]);
        return is_point_constraint(state, c) ? Vector3s<Scalar>(-relative) : Vector3s<Scalar>(-direction(c).dot(relative), 0, 0);
      },
      direction,
      [](std::size_t) { return Scalar(0); },
      [&](std::uint32_t p, const Vector3s<Scalar>& delta) { particles.set_velocity(p, particles.velocity(p) + delta); },
      [](std::size_t, const Vector3s<Scalar>&) {},
      [&](std::uint32_t c) { return static_cast<double>(project_distance_velocity(particles, state.constraints, c, state.options.rule)); });
}

template <typename Scalar>
void kick_compliant_constraints(VerletState<Scalar>& state, double dt) {
  DirectProjection<Scalar>& direct = state.plan.direct;
  auto& particles = state.particles;
  const auto inverse_step = static_cast<Scalar>(1.0 / dt);
  for (const std::uint32_t island : state.awake_islands) {
    for (std::uint32_t c = state.islands[island].constraint_begin; c < state.islands[island].constraint_end; ++c) {
      constraint_value(state, c, direct.direction[c]);  // n at the end of the substep
      const Vector3s<Scalar> impulse = inverse_step * direct.multiplier[c];
      const Vector3s<Scalar> along = is_point_constraint(state, c) ? impulse : Vector3s<Scalar>(direct.direction[c] * impulse.x());
      const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
      particles.set_velocity(i, particles.velocity(i) + correction_weight(state, i) * along);
      particles.set_velocity(j, particles.velocity(j) - correction_weight(state, j) * along);
    }
  }
}

#define LIMBER_INSTANTIATE(Scalar)                                              \
  template void prepare_direct_projection<Scalar>(VerletState<Scalar>&);        \
  template void begin_direct_projection<Scalar>(VerletState<Scalar>&, double);  \
  template double direct_projection_step<Scalar>(VerletState<Scalar>&);         \
  template double direct_velocity_projection<Scalar>(VerletState<Scalar>&);      \
  template void kick_compliant_constraints<Scalar>(VerletState<Scalar>&, double);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
