// GCC 12 reports -Wmaybe-uninitialized inside its own AVX-512 intrinsics (GCC bug 105593).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/relaxation/contact_relaxation.hpp"

#include <algorithm>
#include <array>
#include <bit>

#include "limber/kernel/relaxation/coloured_sweep.hpp"
#include "limber/kernel/relaxation/contact_projection.hpp"

namespace limber {
namespace {

using contact_projection::ContactFields;

// One colour's (or the overflow's) slots, as the BlockRunner hands them out.
template <typename Scalar, typename Lanes>
struct ContactStage {
  ContactRowBatches<Scalar>* batches;
  ContactFields<Scalar> fields;
  std::size_t begin, end;
  std::size_t task_count() const { return (end - begin + coloured::kSlotsPerTask - 1) / coloured::kSlotsPerTask; }
  static double project(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const ContactStage*>(context);
    const std::size_t first = stage.begin + task * coloured::kSlotsPerTask;
    const std::size_t last = std::min(stage.end, first + coloured::kSlotsPerTask);
    return contact_projection::project_contact_rows<Lanes>(*stage.batches, first, last, stage.fields);
  }
};

template <typename Scalar, typename Lanes>
double sweep(VerletState<Scalar>& state) {
  RelaxationPlan<Scalar>& plan = state.plan;
  ContactRowBatches<Scalar>& batches = plan.contact_batches;
  auto& p = state.particles;
  const ContactFields<Scalar> fields{p.position_x.data(), p.position_y.data(), p.position_z.data(), p.previous_x.data(),
                                     p.previous_y.data(), p.previous_z.data(), p.inverse_mass.data()};
  using Stage = ContactStage<Scalar, Lanes>;
  double largest = 0;
  for (std::size_t colour = 0; colour < batches.colour_count(); ++colour) {
    const Stage stage{&batches, fields, batches.colour_begin[colour], batches.colour_begin[colour + 1]};
    // The sequential sweep is the thesis's loop, and a plan without a runner (the direct
    // solver's, or a scene with no distance constraints to colour) has no threads: one thread.
    if (state.options.order == SweepOrder::coloured && plan.runner.operator->() != nullptr) {
      largest = std::max(largest, coloured::run_stage(plan, stage.end - stage.begin, stage.task_count(), &Stage::project, &stage));
    } else {
      for (std::size_t task = 0; task < stage.task_count(); ++task) largest = std::max(largest, Stage::project(&stage, task));
    }
  }
  const std::size_t overflow = batches.overflow_begin();
  if (overflow < batches.slot_count()) {
    largest = std::max(largest, static_cast<double>(contact_projection::project_contact_rows<ScalarLanes<Scalar>>(
                                    batches, overflow, batches.slot_count(), fields)));
  }
  return largest;
}

// The lowest colour that moves none of the row's movable particles, or kNoContactColour.
template <typename Scalar>
std::uint8_t colour_row(VerletState<Scalar>& state, const ContactRow& row, std::uint32_t max_colours) {
  ContactRowSet& set = state.contact_rows;
  const auto& w = state.particles.inverse_mass;
  std::uint64_t taken = 0;
  for (std::size_t k = 0; k < kContactRowParticles; ++k) {
    if (row.coefficient[k] != 0 && w[row.particle[k]] > 0) taken |= set.particle_colours[row.particle[k]];
  }
  const auto colour = static_cast<std::uint32_t>(std::countr_one(taken));
  if (colour >= max_colours) return kNoContactColour;
  for (std::size_t k = 0; k < kContactRowParticles; ++k) {
    if (row.coefficient[k] != 0 && w[row.particle[k]] > 0) set.particle_colours[row.particle[k]] |= std::uint64_t{1} << colour;
  }
  return static_cast<std::uint8_t>(colour);
}

template <typename Scalar>
void fill_slot(ContactRowBatches<Scalar>& batches, std::size_t slot, const ContactRow& row, std::uint32_t r) {
  using Index = typename ContactRowBatches<Scalar>::Index;
  for (std::size_t k = 0; k < kContactRowParticles; ++k) {
    batches.particle[k][slot] = static_cast<Index>(row.particle[k]);
    batches.coefficient[k][slot] = static_cast<Scalar>(row.coefficient[k]);
  }
  batches.normal_x[slot] = static_cast<Scalar>(row.normal.x());
  batches.normal_y[slot] = static_cast<Scalar>(row.normal.y());
  batches.normal_z[slot] = static_cast<Scalar>(row.normal.z());
  batches.offset[slot] = static_cast<Scalar>(row.offset);
  batches.friction[slot] = static_cast<Scalar>(row.friction);
  batches.row[slot] = r;
}

}  // namespace

template <typename Scalar>
void build_contact_batches(VerletState<Scalar>& state) {
  ContactRowSet& set = state.contact_rows;
  ContactRowBatches<Scalar>& batches = state.plan.contact_batches;
  using Index = typename ContactRowBatches<Scalar>::Index;
  const auto null_particle = static_cast<Index>(state.particles.null_particle());
  batches.clear();
  if (set.rows.empty()) return;
  const std::uint32_t max_colours = std::min<std::uint32_t>(kMaxContactColours, std::max<std::uint32_t>(1, state.options.max_colours));
  set.colour.resize(set.rows.size());
  set.colour_count = 0;
  for (std::size_t r = 0; r < set.rows.size(); ++r) {
    set.colour[r] = colour_row(state, set.rows[r], max_colours);
    if (set.colour[r] != kNoContactColour) set.colour_count = std::max<std::uint32_t>(set.colour_count, set.colour[r] + 1u);
  }
  for (const ContactRow& row : set.rows) {
    for (std::uint32_t p : row.particle) set.particle_colours[p] = 0;
  }
  // A counting sort by colour (the overflow last), rows in detection order inside each.
  std::array<std::uint32_t, kMaxContactColours + 2> start{};
  for (std::uint8_t colour : set.colour) ++start[(colour == kNoContactColour ? set.colour_count : colour) + 1u];
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  set.order.resize(set.rows.size());
  for (std::size_t r = 0; r < set.rows.size(); ++r) {
    const std::uint32_t bucket = set.colour[r] == kNoContactColour ? set.colour_count : set.colour[r];
    set.order[start[bucket]++] = static_cast<std::uint32_t>(r);
  }
  std::size_t next = 0;
  for (std::uint32_t colour = 0; colour < set.colour_count; ++colour) {
    for (; next < start[colour]; ++next) fill_slot(batches, batches.push(null_particle), set.rows[set.order[next]], set.order[next]);
    batches.close_colour(null_particle);
  }
  for (; next < set.rows.size(); ++next) fill_slot(batches, batches.push(null_particle), set.rows[set.order[next]], set.order[next]);
}

template <typename Scalar>
double contact_position_sweep(VerletState<Scalar>& state) {
  if (state.plan.contact_batches.slot_count() == 0) return 0;
  return state.options.simd ? sweep<Scalar, SimdLanes<Scalar>>(state) : sweep<Scalar, ScalarLanes<Scalar>>(state);
}

#define LIMBER_INSTANTIATE(Scalar)                                     \
  template void build_contact_batches<Scalar>(VerletState<Scalar>&);   \
  template double contact_position_sweep<Scalar>(VerletState<Scalar>&);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
