#include "limber/kernel/relaxation/relaxation.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>

#include "limber/kernel/relaxation/batch_projection.hpp"
#include "limber/kernel/relaxation/coloured_sweep.hpp"
#include "limber/kernel/relaxation/direct_projection.hpp"
#include "limber/kernel/relaxation/distance_projection.hpp"
#include "limber/kernel/relaxation/gauss_seidel.hpp"
#include "limber/kernel/relaxation/joint_relaxation.hpp"
#include "limber/kernel/relaxation/joint_trees.hpp"
#include "limber/layouts/graph/compressed_rows.hpp"
#include "limber/layouts/graph/constraint_colouring.hpp"

namespace limber {
namespace {

using coloured::kParticlesPerTask;
// Below this many slots a colour runs on one thread. Measured (bench/speed.md, "The data-oriented core:
// SIMD, threads, layouts"): handing a
// stage to two threads costs ~4.6 us (either strategy) and a slot ~0.8 ns, so a colour pays
// for the second core from ~12k slots; chains of 10^4 links (5k per colour) ran 1.6x slower
// on two threads, 10^5 links 1.9x faster.
constexpr std::uint32_t kDefaultParallelMinimumSlots = 16384;

// Fills the batches with the constraints of `islands` (state.awake_islands when stepping).
template <typename Scalar>
void build_batches(VerletState<Scalar>& state, const std::vector<std::uint32_t>& islands) {
  RelaxationPlan<Scalar>& plan = state.plan;
  ConstraintBatches<Scalar>& batches = plan.batches;
  const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
  const AlignedArray<Scalar>& inverse_mass = state.particles.inverse_mass;
  using Index = typename ConstraintBatches<Scalar>::Index;
  const auto null_particle = static_cast<Index>(state.particles.null_particle());
  auto push = [&](std::uint32_t c) {
    const std::uint32_t i = constraints.particle_i[c], j = constraints.particle_j[c];
    Scalar s_i = 0, s_j = 0;
    correction_shares(state.options.rule, inverse_mass[i], inverse_mass[j], s_i, s_j);
    batches.push(static_cast<Index>(i), static_cast<Index>(j), constraints.rest_length[c], s_i, s_j);
  };
  batches.clear();
  for (std::uint32_t colour = 0; colour < state.colour_count; ++colour) {
    for (std::uint32_t k : islands) {
      const Island& island = state.islands[k];
      for (std::uint32_t c = island.constraint_begin; c < island.constraint_end; ++c) {
        if (state.constraint_colour[c] == colour) push(c);
      }
    }
    batches.close_colour(null_particle);
  }
  const bool forward = state.options.direction == SweepDirection::pinned_first;
  const auto push_overflow = [&](std::uint32_t c) {
    const bool movable = inverse_mass[constraints.particle_i[c]] > 0 || inverse_mass[constraints.particle_j[c]] > 0;
    if (state.constraint_colour[c] == kNoColour && movable && !held_by_joint_tree(state, c)) push(c);
  };
  for (std::size_t n = 0; n < islands.size(); ++n) {
    const Island& island = state.islands[islands[forward ? n : islands.size() - 1 - n]];
    for (std::uint32_t c = island.constraint_begin; c < island.constraint_end; ++c) {
      push_overflow(forward ? c : island.constraint_end - 1 - (c - island.constraint_begin));
    }
  }

  plan.particle_tasks.clear();
  for (std::uint32_t k : islands) {
    const Island& island = state.islands[k];
    for (std::uint32_t p = island.particle_begin; p < island.particle_end; p += kParticlesPerTask) {
      plan.particle_tasks.emplace_back(p, std::min<std::uint32_t>(island.particle_end, p + kParticlesPerTask));
    }
  }
  if (state.options.solver == RelaxationSolver::jacobi) {
    for (const auto& [begin, end] : plan.particle_tasks) {
      std::fill(plan.inverse_count.begin() + begin, plan.inverse_count.begin() + end, Scalar(0));
    }
    for (std::size_t slot = 0; slot < batches.slot_count(); ++slot) {
      if (batches.share_i[slot] > 0) plan.inverse_count[batches.particle_i[slot]] += 1;
      if (batches.share_j[slot] > 0) plan.inverse_count[batches.particle_j[slot]] += 1;
    }
    for (const auto& [begin, end] : plan.particle_tasks) {
      for (std::uint32_t p = begin; p < end; ++p) {
        if (plan.inverse_count[p] > 0) plan.inverse_count[p] = Scalar(1) / plan.inverse_count[p];
      }
    }
  }
  plan.built_for = state.awake_generation;
}

// A position sweep of `kKernel` over the layout relaxation runs on.
template <typename Scalar, typename Lanes, coloured::Kernel kKernel>
double coloured_sweep(VerletState<Scalar>& state, Scalar over_relaxation) {
  RelaxationPlan<Scalar>& plan = state.plan;
  switch (plan.layout) {
    case ParticleLayout::aos:
      return coloured::coloured_sweep<Scalar, Lanes, kKernel>(state, InterleavedPositions<Scalar, 1>(plan.array_of_structures),
                                                              over_relaxation);
    case ParticleLayout::aosoa:
      return coloured::coloured_sweep<Scalar, Lanes, kKernel>(
          state, InterleavedPositions<Scalar, kLanesPerLine<Scalar>>(plan.blocked_structures), over_relaxation);
    case ParticleLayout::soa:
    case ParticleLayout::automatic: break;  // resolved by prepare_relaxation_plan
  }
  return coloured::coloured_sweep<Scalar, Lanes, kKernel>(state, SoaPositions<Scalar>(state.particles), over_relaxation);
}

template <typename Scalar, coloured::Kernel kKernel>
double coloured_sweep(VerletState<Scalar>& state, Scalar over_relaxation) {
  return state.options.simd ? coloured_sweep<Scalar, SimdLanes<Scalar>, kKernel>(state, over_relaxation)
                            : coloured_sweep<Scalar, ScalarLanes<Scalar>, kKernel>(state, over_relaxation);
}

// Applies `copy(store)` to the interleaved store in use, if any.
template <typename Scalar, typename Function>
void with_interleaved(VerletState<Scalar>& state, Function&& copy) {
  if (state.plan.layout == ParticleLayout::aos) copy(state.plan.array_of_structures);
  if (state.plan.layout == ParticleLayout::aosoa) copy(state.plan.blocked_structures);
}

// SoA where most blocks join runs of consecutive particles at both ends (they load as plain
// vectors: chains in depth-parity order); otherwise AoS, whose records load and transpose
// faster than SoA gathers (trees, grids, piles of ragdolls: about 2x in both precisions).
// The sequential sweep reads the ParticleBuffer itself.
template <typename Scalar>
ParticleLayout automatic_layout(VerletState<Scalar>& state) {
  if (state.options.order == SweepOrder::sequential) return ParticleLayout::soa;
  std::vector<std::uint32_t> all_islands(state.islands.size());
  for (std::uint32_t k = 0; k < all_islands.size(); ++k) all_islands[k] = k;
  build_batches(state, all_islands);
  const auto& consecutive = state.plan.batches.consecutive;
  const auto both = std::count(consecutive.begin(), consecutive.end(), std::uint8_t{3});
  return 2 * both >= static_cast<std::ptrdiff_t>(consecutive.size()) ? ParticleLayout::soa : ParticleLayout::aos;
}

// Long-range attachments: the rest length of the shortest constraint path from each particle
// to a pinned particle (Dijkstra from all pins at once), the pin it leads to.
template <typename Scalar>
void prepare_long_range_attachments(VerletState<Scalar>& state) {
  const auto& particles = state.particles;
  const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
  RelaxationPlan<Scalar>& plan = state.plan;
  std::vector<std::pair<std::uint32_t, std::pair<std::uint32_t, double>>> edges;
  for (std::uint32_t c = 0; c < constraints.size(); ++c) {
    const double length = constraints.rest_length[c];
    edges.push_back({constraints.particle_i[c], {constraints.particle_j[c], length}});
    edges.push_back({constraints.particle_j[c], {constraints.particle_i[c], length}});
  }
  const auto neighbours = group_by_row(particles.size(), edges);
  std::vector<double> distance(particles.size(), std::numeric_limits<double>::infinity());
  plan.attachment_pin.assign(particles.size(), particles.null_particle());
  using Entry = std::pair<double, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (std::uint32_t p = 0; p < particles.size(); ++p) {
    if (particles.inverse_mass[p] != Scalar(0)) continue;
    distance[p] = 0, plan.attachment_pin[p] = p;
    queue.emplace(0.0, p);
  }
  while (!queue.empty()) {
    const auto [d, p] = queue.top();
    queue.pop();
    if (d > distance[p]) continue;
    for (const auto& [other, length] : neighbours.row(p)) {
      if (d + length >= distance[other]) continue;
      distance[other] = d + length, plan.attachment_pin[other] = plan.attachment_pin[p];
      queue.emplace(distance[other], other);
    }
  }
  plan.attachment_length.assign(particles.size(), Scalar(0));
  for (std::uint32_t p = 0; p < particles.size(); ++p) {
    if (particles.inverse_mass[p] == Scalar(0)) plan.attachment_pin[p] = particles.null_particle();  // pins hang from nothing
    if (plan.attachment_pin[p] != particles.null_particle()) plan.attachment_length[p] = static_cast<Scalar>(distance[p]);
  }
}

// Wakes the helper threads, when some colour is big enough to be split across them.
template <typename Scalar>
void begin_helpers(RelaxationPlan<Scalar>& plan) {
  bool parallel = false;
  for (std::size_t k = 0; k < plan.batches.colour_count(); ++k) {
    parallel = parallel || plan.batches.colour_begin[k + 1] - plan.batches.colour_begin[k] >= plan.parallel_minimum_slots;
  }
  for (std::size_t k = 0; k < plan.joint_batches.colour_count(); ++k) {
    parallel = parallel || plan.joint_batches.colour_begin[k + 1] - plan.joint_batches.colour_begin[k] >= plan.parallel_minimum_slots;
  }
  if (parallel || joint_trees_on_threads(plan)) plan.runner->begin();
}

// The previous positions and the velocities as the coloured kernels read them (SoA).
template <typename Scalar>
SoaPositions<Scalar> previous_positions(ParticleBuffer<Scalar>& particles) {
  return {particles.previous_x.data(), particles.previous_y.data(), particles.previous_z.data()};
}
template <typename Scalar>
SoaPositions<Scalar> velocities(ParticleBuffer<Scalar>& particles) {
  return {particles.velocity_x.data(), particles.velocity_y.data(), particles.velocity_z.data()};
}

// Every awake constraint's gradient at `positions` (the previous positions: the substep's start;
// or the current ones), into the batches or, for the sequential sweep and the direct solver,
// into plan.constraint_gradient.
template <typename Scalar>
void store_gradients(VerletState<Scalar>& state, SoaPositions<Scalar> positions) {
  if (state.options.order == SweepOrder::sequential || state.options.solver == RelaxationSolver::direct) {
    const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
    const auto at = [&](std::uint32_t p) { return Eigen::Matrix<Scalar, 3, 1>(positions.x[p], positions.y[p], positions.z[p]); };
    for (const std::uint32_t k : state.awake_islands) {
      for (std::uint32_t c = state.islands[k].constraint_begin; c < state.islands[k].constraint_end; ++c) {
        state.plan.constraint_gradient[c] = constraint_gradient(at(constraints.particle_i[c]), at(constraints.particle_j[c]), constraints.rest_length[c]);
      }
    }
    return;
  }
  if (state.options.simd) {
    coloured::store_all_gradients<Scalar, SimdLanes<Scalar>>(state, positions);
  } else {
    coloured::store_all_gradients<Scalar, ScalarLanes<Scalar>>(state, positions);
  }
}

}  // namespace

template <typename Scalar>
double project_long_range_attachments(VerletState<Scalar>& state) {
  auto& particles = state.particles;
  const RelaxationPlan<Scalar>& plan = state.plan;
  const std::uint32_t none = particles.null_particle();
  double largest = 0;
  for (const std::uint32_t k : state.awake_islands) {
    for (std::uint32_t p = state.islands[k].particle_begin; p < state.islands[k].particle_end; ++p) {
      const std::uint32_t pin = plan.attachment_pin[p];
      if (pin == none) continue;
      const Eigen::Matrix<Scalar, 3, 1> offset = particles.position(p) - particles.position(pin);
      const Scalar length = offset.norm(), allowed = plan.attachment_length[p];
      if (length <= allowed) continue;  // unilateral: a tether, not a rod
      particles.set_position(p, particles.position(pin) + offset * (allowed / length));
      largest = std::max(largest, static_cast<double>(length - allowed));
    }
  }
  return largest;
}

template <typename Scalar>
void prepare_relaxation_plan(VerletState<Scalar>& state) {
  const VerletOptions& options = state.options;
  if (options.threads < 0 || options.threads > kMaxThreads) {
    throw std::invalid_argument("options: threads must be 0 (automatic) or in [1, " + std::to_string(kMaxThreads) + "]");
  }
  prepare_joint_rows(state);
  prepare_joint_trees(state);
  if (options.compliance != 0 && options.solver != RelaxationSolver::direct) {
    throw std::invalid_argument("options: compliance needs the direct solver (Gauss-Seidel and Jacobi sweeps treat every constraint as rigid)");
  }
  if (options.long_range_attachments) {
    if (options.layout == ParticleLayout::aos || options.layout == ParticleLayout::aosoa) {
      throw std::invalid_argument("options: long-range attachments work on the SoA layout");
    }
    prepare_long_range_attachments(state);
  }
  // The rattle rule's start gradients, per constraint, where no batches hold them.
  if (uses_rattle(state) && (options.solver == RelaxationSolver::direct || options.order == SweepOrder::sequential)) {
    state.plan.constraint_gradient.assign(state.constraints.size(), Eigen::Matrix<Scalar, 3, 1>::Zero());
  }
  if (options.solver == RelaxationSolver::direct) {
    if (options.layout == ParticleLayout::aos || options.layout == ParticleLayout::aosoa || options.order == SweepOrder::sequential) {
      throw std::invalid_argument("options: the direct solver works on the SoA layout and has no sweep order");
    }
    state.plan.layout = ParticleLayout::soa;
    prepare_direct_projection(state);
    return;
  }
  if (options.max_colours < 1 || options.max_colours > kMaxColours) {
    throw std::invalid_argument("options: max_colours must be in [1, 64]");
  }
  if (options.order == SweepOrder::sequential &&
      ((options.layout != ParticleLayout::soa && options.layout != ParticleLayout::automatic) ||
       options.solver == RelaxationSolver::jacobi)) {
    throw std::invalid_argument("options: the sequential sweep is scalar Gauss-Seidel over the SoA layout only");
  }
  const DistanceConstraintBuffer<Scalar>& constraints = state.constraints;
  std::vector<bool> movable(state.particles.size());
  for (std::size_t p = 0; p < movable.size(); ++p) movable[p] = state.particles.inverse_mass[p] > 0;
  // Only constraints between two movable particles enter a colour: the others go to the overflow
  // (and those a joint tree holds, to neither).
  std::vector<std::uint32_t> order;
  order.reserve(constraints.size());
  for (std::uint32_t c = 0; c < constraints.size(); ++c) {
    if (movable[constraints.particle_i[c]] && movable[constraints.particle_j[c]] && !held_by_joint_tree(state, c)) order.push_back(c);
  }
  ConstraintColouring colouring =
      colour_constraints({constraints.particle_i.data(), constraints.size()},
                         {constraints.particle_j.data(), constraints.size()}, order, movable, options.max_colours);
  state.constraint_colour = std::move(colouring.colour);
  state.colour_count = colouring.colour_count();

  RelaxationPlan<Scalar>& plan = state.plan;
  const std::size_t lanes = ConstraintBatches<Scalar>::kBlockLanes;
  plan.batches.reserve(constraints.size() + state.colour_count * (lanes - 1), state.colour_count);
  plan.particle_tasks.reserve(state.islands.size() + state.particles.size() / kParticlesPerTask + 1);
  if (options.solver == RelaxationSolver::jacobi) {
    for (auto* array : {&plan.sum_x, &plan.sum_y, &plan.sum_z, &plan.inverse_count}) {
      array->assign(state.particles.capacity(), Scalar(0));
    }
  }
  plan.parallel_minimum_slots = options.parallel_minimum_slots > 0 ? options.parallel_minimum_slots : kDefaultParallelMinimumSlots;
  // Automatic threads only when some colour is big enough to be split: a small scene starts none.
  std::vector<std::uint32_t> colour_size(state.colour_count, 0);
  for (const std::uint8_t colour : state.constraint_colour) {
    if (colour != kNoColour) ++colour_size[colour];
  }
  // A crowd of joint trees (kParallelMinimumTreeIslands islands or more) is big as well: its
  // islands are the tasks (joint_trees.hpp).
  const bool crowd = plan.joint_trees.island_components.entries.size() >= kParallelMinimumTreeIslands;
  const bool big = crowd || std::any_of(colour_size.begin(), colour_size.end(), [&](std::uint32_t n) { return n >= plan.parallel_minimum_slots; });
  const int threads = options.threads > 0 ? options.threads
                      : big               ? static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))
                                          : 1;
  plan.runner.reset(options.threading, threads, options.tasks);
  if (threads == 1) plan.parallel_minimum_slots = ~std::uint32_t{0};
  plan.layout = options.layout;
  if (options.layout == ParticleLayout::automatic) {
    // Joint rows and trees read and write the SoA arrays.
    const bool soa = options.long_range_attachments || !state.joint_rows.empty() || plan.joint_trees.active();
    plan.layout = soa ? ParticleLayout::soa : automatic_layout(state);
  }
  plan.built_for = ~std::uint64_t{0};
  with_interleaved(state, [&](auto& store) {
    store.resize_for(state.particles);
    store.copy_from(state.particles, 0, state.particles.capacity());
  });
}


template <typename Scalar>
void begin_relaxation(VerletState<Scalar>& state, double dt) {
  RelaxationPlan<Scalar>& plan = state.plan;
  plan.awake_constraints = 0;
  for (std::uint32_t k : state.awake_islands) {
    const Island& island = state.islands[k];
    plan.awake_constraints += island.constraint_end - island.constraint_begin;
    // What the joint trees hold, the sweeps do not project.
    for (std::uint32_t c = island.constraint_begin; c < island.constraint_end && plan.joint_trees.active(); ++c) {
      plan.awake_constraints -= held_by_joint_tree(state, c) ? 1 : 0;
    }
  }
  // Joint rows first: whether to wake the helpers depends on their colours too.
  if (!state.joint_rows.empty()) {
    if (plan.joint_built_for != state.awake_generation) build_joint_batches(state), plan.joint_built_for = state.awake_generation;
    begin_joint_rows(state, dt);
  }
  if (state.options.solver != RelaxationSolver::direct && state.options.order != SweepOrder::sequential) {
    if (plan.built_for != state.awake_generation) build_batches(state, state.awake_islands);
    with_interleaved(state, [&](auto& store) {
      for (std::uint32_t k : state.awake_islands) {
        store.copy_from(state.particles, state.islands[k].particle_begin, state.islands[k].particle_end);
      }
    });
    begin_helpers(plan);
  }
  if (uses_rattle(state)) store_gradients(state, previous_positions(state.particles));
  if (state.options.solver == RelaxationSolver::direct) begin_direct_projection(state, dt);
  if (plan.joint_trees.active()) begin_joint_trees(state, dt);
}

template <typename Scalar>
void begin_velocity_projection(VerletState<Scalar>& state) {
  if (state.options.solver != RelaxationSolver::direct && state.options.order != SweepOrder::sequential) begin_helpers(state.plan);
  store_gradients(state, SoaPositions<Scalar>(state.particles));
}

template <typename Scalar>
double velocity_sweep(VerletState<Scalar>& state) {
  if (state.options.solver == RelaxationSolver::direct) return direct_velocity_projection(state);
  state.counters.constraint_projections += state.plan.awake_constraints;
  const double largest = state.options.order == SweepOrder::sequential ? gauss_seidel_velocity_sweep(state)
      : state.options.simd
      ? coloured::coloured_sweep<Scalar, SimdLanes<Scalar>, coloured::Kernel::velocity>(state, velocities(state.particles), Scalar(1))
      : coloured::coloured_sweep<Scalar, ScalarLanes<Scalar>, coloured::Kernel::velocity>(state, velocities(state.particles), Scalar(1));
  return std::max(largest, joint_velocity_sweep(state));
}

template <typename Scalar>
void end_velocity_projection(VerletState<Scalar>& state) {
  if (state.options.solver != RelaxationSolver::direct && state.options.order != SweepOrder::sequential) state.plan.runner->end();
}

template <typename Scalar>
double relaxation_sweep(VerletState<Scalar>& state, double over_relaxation) {
  if (state.options.solver == RelaxationSolver::direct) return direct_projection_step(state);
  state.counters.constraint_projections += state.plan.awake_constraints;
  const auto omega = static_cast<Scalar>(over_relaxation);
  const double largest = state.options.order == SweepOrder::sequential ? gauss_seidel_sweep(state, over_relaxation)
                         : uses_rattle(state) ? coloured_sweep<Scalar, coloured::Kernel::start_gradient>(state, omega)
                                              : coloured_sweep<Scalar, coloured::Kernel::pbd>(state, omega);
  return std::max(largest, joint_position_sweep(state));
}

template <typename Scalar>
void end_relaxation(VerletState<Scalar>& state) {
  if (state.options.order == SweepOrder::sequential || state.options.solver == RelaxationSolver::direct) return;
  state.plan.runner->end();
  with_interleaved(state, [&](auto& store) {
    for (std::uint32_t k : state.awake_islands) {
      store.copy_positions_to(state.particles, state.islands[k].particle_begin, state.islands[k].particle_end);
    }
  });
}

template <typename Scalar>
void contact_particles_to_buffer(VerletState<Scalar>& state) {
  with_interleaved(state, [&](auto& store) {
    for (std::uint32_t p : state.contact_particles) store.copy_position_to(state.particles, p);
  });
}

template <typename Scalar>
void contact_particles_from_buffer(VerletState<Scalar>& state) {
  with_interleaved(state, [&](auto& store) {
    for (std::uint32_t p : state.contact_particles) store.copy_position_from(state.particles, p);
  });
}

#define LIMBER_INSTANTIATE(Scalar)                                                  \
  template void prepare_relaxation_plan<Scalar>(VerletState<Scalar>&);              \
  template void begin_relaxation<Scalar>(VerletState<Scalar>&, double);             \
  template double relaxation_sweep<Scalar>(VerletState<Scalar>&, double);           \
  template void end_relaxation<Scalar>(VerletState<Scalar>&);                       \
  template void contact_particles_to_buffer<Scalar>(VerletState<Scalar>&);          \
  template void contact_particles_from_buffer<Scalar>(VerletState<Scalar>&);        \
  template double project_long_range_attachments<Scalar>(VerletState<Scalar>&);     \
  template void begin_velocity_projection<Scalar>(VerletState<Scalar>&);           \
  template double velocity_sweep<Scalar>(VerletState<Scalar>&);                     \
  template void end_velocity_projection<Scalar>(VerletState<Scalar>&);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
