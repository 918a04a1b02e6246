#include "limber/kernel/relaxation/joint_relaxation.hpp"

#include <algorithm>
#include <stdexcept>

#include "limber/kernel/relaxation/coloured_sweep.hpp"
#include "limber/kernel/relaxation/joint_projection.hpp"
#include "limber/layouts/graph/constraint_colouring.hpp"

namespace limber {
namespace {

using joint_projection::JointFields;
using joint_projection::Stage;

constexpr std::size_t kKinds = static_cast<std::size_t>(kJointRowKinds);

// One colour-and-kind run of blocks, as the BlockRunner hands it out in tasks of kSlotsPerTask.
template <typename Scalar, typename Lanes, Stage kStage>
struct JointStage {
  JointRowBatches<Scalar>* batches;
  JointFields<Scalar> fields;
  JointRowKind kind;
  std::size_t begin, end;
  Scalar step;
  std::size_t task_count() const { return (end - begin + coloured::kSlotsPerTask - 1) / coloured::kSlotsPerTask; }
  static double project(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const JointStage*>(context);
    const std::size_t first = stage.begin + task * coloured::kSlotsPerTask;
    const std::size_t last = std::min(stage.end, first + coloured::kSlotsPerTask);
    return joint_projection::project_joint_rows<Lanes, kStage>(*stage.batches, stage.kind, first, last, stage.fields, stage.step);
  }
};

template <typename Scalar>
JointFields<Scalar> position_fields(ParticleBuffer<Scalar>& particles) {
  return {particles.position_x.data(), particles.position_y.data(), particles.position_z.data(),
          particles.previous_x.data(), particles.previous_y.data(), particles.previous_z.data(), particles.inverse_mass.data()};
}
template <typename Scalar>
JointFields<Scalar> velocity_fields(ParticleBuffer<Scalar>& particles) {
  return {particles.velocity_x.data(), particles.velocity_y.data(), particles.velocity_z.data(),
          particles.position_x.data(), particles.position_y.data(), particles.position_z.data(), particles.inverse_mass.data()};
}

template <typename Scalar, typename Lanes, Stage kStage>
double sweep(VerletState<Scalar>& state, JointFields<Scalar> fields) {
  RelaxationPlan<Scalar>& plan = state.plan;
  JointRowBatches<Scalar>& batches = plan.joint_batches;
  double largest = 0;
  std::size_t block = 0;
  for (std::size_t colour = 0; colour < batches.colour_count(); ++colour) {
    // Runs of one kind inside the colour: consecutive blocks with the same kind.
    for (std::size_t slot = batches.colour_begin[colour]; slot < batches.colour_begin[colour + 1];) {
      const std::uint8_t kind = batches.block_kind[block];
      std::size_t end = slot;
      while (end < batches.colour_begin[colour + 1] && batches.block_kind[block] == kind) {
        end += JointRowBatches<Scalar>::kBlockLanes, ++block;
      }
      const JointStage<Scalar, Lanes, kStage> stage{&batches, fields, static_cast<JointRowKind>(kind), slot, end, plan.joint_step};
      using Stage = JointStage<Scalar, Lanes, kStage>;
      if (state.options.order == SweepOrder::coloured) {
        largest = std::max(largest, coloured::run_stage(plan, end - slot, stage.task_count(), &Stage::project, &stage));
      } else {  // the sequential sweep is the thesis's loop: one thread
        for (std::size_t task = 0; task < stage.task_count(); ++task) largest = std::max(largest, Stage::project(&stage, task));
      }
      slot = end;
    }
  }
  for (std::size_t slot = batches.overflow_begin(); slot < batches.slot_count(); ++slot) {
    const auto kind = static_cast<JointRowKind>(batches.overflow_kind[slot - batches.overflow_begin()]);
    largest = std::max(largest, static_cast<double>(joint_projection::project_joint_rows<ScalarLanes<Scalar>, kStage>(
                                    batches, kind, slot, slot + 1, fields, plan.joint_step)));
  }
  return largest;
}

template <typename Scalar, Stage kStage>
double sweep(VerletState<Scalar>& state, JointFields<Scalar> fields) {
  if (state.joint_rows.empty()) return 0;
  return state.options.simd ? sweep<Scalar, SimdLanes<Scalar>, kStage>(state, fields) : sweep<Scalar, ScalarLanes<Scalar>, kStage>(state, fields);
}

// Writes row r into slot `slot`.
template <typename Scalar>
void fill_slot(JointRowBatches<Scalar>& batches, std::size_t slot, const JointRow& row) {
  using Index = typename JointRowBatches<Scalar>::Index;
  for (std::size_t k = 0; k < kJointRowParticles; ++k) batches.particle[k][slot] = static_cast<Index>(row.particle[k]);
  for (std::size_t k = 0; k < kJointRowDirections; ++k) batches.direction[k][slot] = static_cast<Scalar>(row.direction[k]);
  batches.side_a[slot] = static_cast<Scalar>(static_cast<int>(row.side_a));
  batches.side_b[slot] = static_cast<Scalar>(static_cast<int>(row.side_b));
  batches.lower[slot] = static_cast<Scalar>(row.lower), batches.upper[slot] = static_cast<Scalar>(row.upper);
  batches.target[slot] = static_cast<Scalar>(row.target), batches.target_velocity[slot] = static_cast<Scalar>(row.target_velocity);
  batches.blend[slot] = static_cast<Scalar>(row.blend);
  batches.stiffness[slot] = static_cast<Scalar>(row.stiffness), batches.damping[slot] = static_cast<Scalar>(row.damping);
  batches.friction[slot] = static_cast<Scalar>(row.friction);
}

}  // namespace

template <typename Scalar>
void prepare_joint_rows(VerletState<Scalar>& state) {
  JointRowSet& rows = state.joint_rows;
  if (rows.empty()) return;
  const VerletOptions& options = state.options;
  const auto refuse = [](const char* what) {
    throw std::invalid_argument(std::string("options: joints beyond spherical joints at limb ends (frames, anchors off the ends, "
                                            "hinges, limits, friction, drives) need ") + what);
  };
  if (options.rule != RelaxationRule::weighted) refuse("the weighted rule (their rows move clusters of particles by inverse mass)");
  if (options.solver != RelaxationSolver::gauss_seidel) refuse("the Gauss-Seidel solver (not Jacobi or the direct solver)");
  if (options.layout == ParticleLayout::aos || options.layout == ParticleLayout::aosoa) refuse("the SoA layout");
  std::vector<bool> movable(state.particles.size() + 1, false);
  for (std::size_t p = 0; p < state.particles.size(); ++p) movable[p] = state.particles.inverse_mass[p] > 0;
  const auto particles_of = [&](std::size_t r) { return std::span<const std::uint32_t>(rows.rows[r].particle); };
  ConstraintColouring colouring = colour_rows(rows.rows.size(), particles_of, movable, options.max_colours);
  rows.colour = std::move(colouring.colour);
  rows.colour_count = colouring.colour_count();
  RelaxationPlan<Scalar>& plan = state.plan;
  const std::size_t lanes = JointRowBatches<Scalar>::kBlockLanes;
  plan.joint_batches.reserve(rows.rows.size() + (rows.colour_count * kKinds + 1) * lanes, rows.colour_count);
  plan.joint_row_order.assign(rows.rows.size(), 0);
  plan.joint_bucket.assign(rows.colour_count * kKinds + 2, 0);
}

template <typename Scalar>
void build_joint_batches(VerletState<Scalar>& state) {
  const JointRowSet& rows = state.joint_rows;
  if (rows.empty()) return;
  RelaxationPlan<Scalar>& plan = state.plan;
  JointRowBatches<Scalar>& batches = plan.joint_batches;
  using Index = typename JointRowBatches<Scalar>::Index;
  const auto null_particle = static_cast<Index>(state.particles.null_particle());
  // Counting sort of the awake rows by (colour, kind); the overflow is the last bucket.
  std::vector<std::uint32_t>& bucket = plan.joint_bucket;
  std::fill(bucket.begin(), bucket.end(), 0u);
  const std::size_t overflow = rows.colour_count * kKinds;
  const auto bucket_of = [&](std::size_t r) {
    return rows.colour[r] == kNoColour ? overflow : rows.colour[r] * kKinds + static_cast<std::size_t>(rows.rows[r].kind);
  };
  // Rows of sleeping islands, and rows a joint tree holds (joint_trees.hpp), are left out.
  const std::vector<std::uint8_t>& held = plan.joint_trees.tree_row;
  const auto skipped = [&](std::size_t r) { return state.islands[rows.rows[r].island].sleeping || (!held.empty() && held[r]); };
  std::size_t awake = 0;
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    if (skipped(r)) continue;
    ++bucket[bucket_of(r) + 1], ++awake;
  }
  for (std::size_t k = 1; k < bucket.size(); ++k) bucket[k] += bucket[k - 1];
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    if (skipped(r)) continue;
    plan.joint_row_order[bucket[bucket_of(r)]++] = static_cast<std::uint32_t>(r);
  }
  // bucket[k] is now the end of bucket k; bucket k begins where k − 1 ended.
  batches.clear();
  std::size_t next = 0;
  for (std::size_t colour = 0; colour < rows.colour_count; ++colour) {
    for (std::size_t kind = 0; kind < kKinds; ++kind) {
      const std::size_t run_begin = batches.slot_count();
      for (const std::size_t end = bucket[colour * kKinds + kind]; next < end; ++next) {
        fill_slot(batches, batches.push(null_particle), rows.rows[plan.joint_row_order[next]]);
      }
      batches.close_kind(null_particle, static_cast<std::uint8_t>(kind), run_begin);
    }
    batches.close_colour();
  }
  for (; next < awake; ++next) {
    const std::uint32_t r = plan.joint_row_order[next];
    fill_slot(batches, batches.push(null_particle), rows.rows[r]);
    batches.overflow_row.push_back(r);
    batches.overflow_kind.push_back(static_cast<std::uint8_t>(rows.rows[r].kind));
  }
}

template <typename Scalar>
void begin_joint_rows(VerletState<Scalar>& state, double h) {
  state.plan.joint_step = static_cast<Scalar>(h);
  auto& lambda = state.plan.joint_batches.lambda;
  std::fill(lambda.begin(), lambda.end(), Scalar(0));
}

template <typename Scalar>
double joint_position_sweep(VerletState<Scalar>& state) {
  return sweep<Scalar, Stage::positions>(state, position_fields(state.particles));
}

template <typename Scalar>
double joint_velocity_sweep(VerletState<Scalar>& state) {
  return sweep<Scalar, Stage::velocities>(state, velocity_fields(state.particles));
}

#define LIMBER_INSTANTIATE(Scalar)                                        \
  template void prepare_joint_rows<Scalar>(VerletState<Scalar>&);         \
  template void build_joint_batches<Scalar>(VerletState<Scalar>&);        \
  template void begin_joint_rows<Scalar>(VerletState<Scalar>&, double);   \
  template double joint_position_sweep<Scalar>(VerletState<Scalar>&);     \
  template double joint_velocity_sweep<Scalar>(VerletState<Scalar>&);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
