#include "limber/kernel/relaxation/contact_relaxation.hpp"

#include <algorithm>
#include <array>
#include <bit>

#include "limber/kernel/relaxation/coloured_sweep.hpp"
#include "limber/kernel/relaxation/contact_projection.hpp"
#include "limber/kernel/relaxation/tree_contacts.hpp"

namespace limber {
namespace {

using contact_projection::ContactFields;

// One colour's slots, as the BlockRunner hands them out: a task's blocks before the colour's
// pair_begin are projected over places 0 and 1 alone, the rest over all four.
template <typename Scalar, typename Lanes>
struct ContactStage {
  ContactRowBatches<Scalar>* batches;
  ContactFields<Scalar> fields;
  std::size_t begin, pairs, end;
  std::size_t task_count() const { return (end - begin + coloured::kSlotsPerTask - 1) / coloured::kSlotsPerTask; }
  static double project(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const ContactStage*>(context);
    const std::size_t first = stage.begin + task * coloured::kSlotsPerTask;
    const std::size_t last = std::min(stage.end, first + coloured::kSlotsPerTask);
    const std::size_t split = std::clamp(stage.pairs, first, last);
    using contact_projection::project_contact_rows;
    return std::max(project_contact_rows<Lanes, kContactRowSideParticles>(*stage.batches, first, split, stage.fields),
                    project_contact_rows<Lanes, kContactRowParticles>(*stage.batches, split, last, stage.fields));
  }
};

template <typename Scalar, typename Lanes>
double sweep(VerletState<Scalar>& state) {
  RelaxationPlan<Scalar>& plan = state.plan;
  ContactRowBatches<Scalar>& batches = plan.contact_batches;
  auto& p = state.particles;
  const ContactFields<Scalar> fields{p.position_x.data(), p.position_y.data(), p.position_z.data()};
  using Stage = ContactStage<Scalar, Lanes>;
  double largest = 0;
  for (std::size_t colour = 0; colour < batches.colour_count(); ++colour) {
    const Stage stage{&batches, fields, batches.colour_begin[colour], batches.pair_begin[colour], batches.colour_begin[colour + 1]};
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
    largest = std::max(largest, static_cast<double>(contact_projection::project_contact_rows<ScalarLanes<Scalar>, kContactRowParticles>(
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

// Whether the row moves a second side (places 2 and 3): not against static geometry.
bool moves_second_side(const ContactRow& row) {
  return row.coefficient[kContactRowSideParticles] != 0 || row.coefficient[kContactRowSideParticles + 1] != 0;
}

// Writes row r into slot `slot`, with what stays fixed through the substep's sweeps: the shares
// w_k c_k, the effective mass and the start point, in the sweep's own operations and order (so
// an unmoved row has no slip, to the bit).
template <typename Scalar>
void fill_slot(ContactRowBatches<Scalar>& batches, std::size_t slot, const ContactRow& row, std::uint32_t r,
               const ParticleBuffer<Scalar>& particles) {
  using Index = typename ContactRowBatches<Scalar>::Index;
  Scalar denominator = 0, start_x = 0, start_y = 0, start_z = 0;
  for (std::size_t k = 0; k < kContactRowParticles; ++k) {
    const std::uint32_t p = row.particle[k];
    const auto c = static_cast<Scalar>(row.coefficient[k]);
    const Scalar share = particles.inverse_mass[p] * c;
    batches.particle[k][slot] = static_cast<Index>(p);
    batches.coefficient[k][slot] = c, batches.share[k][slot] = share;
    denominator = denominator + share * c;
    start_x = start_x + c * particles.previous_x[p], start_y = start_y + c * particles.previous_y[p];
    start_z = start_z + c * particles.previous_z[p];
  }
  batches.effective_mass[slot] = denominator > Scalar(0) ? Scalar(1) / denominator : Scalar(0);
  batches.start_x[slot] = start_x, batches.start_y[slot] = start_y, batches.start_z[slot] = start_z;
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
    // The joint trees' contacts are theirs (tree_contacts.hpp): in no colour and no batch.
    set.colour[r] = held_by_joint_trees(state, set.rows[r]) ? kTreeContact : colour_row(state, set.rows[r], max_colours);
    if (set.colour[r] < kTreeContact) set.colour_count = std::max<std::uint32_t>(set.colour_count, set.colour[r] + 1u);
  }
  for (const ContactRow& row : set.rows) {
    for (std::uint32_t p : row.particle) set.particle_colours[p] = 0;
  }
  // A counting sort by colour and, inside a colour, rows against static geometry first (the
  // overflow last), rows in detection order inside each bucket. The order inside a colour
  // changes no bit: its rows share no particle they move.
  std::array<std::uint32_t, 2 * kMaxContactColours + 2> start{};
  const auto bucket_of = [&](std::size_t r) -> std::uint32_t {
    if (set.colour[r] == kTreeContact) return 2 * set.colour_count + 1;
    if (set.colour[r] == kNoContactColour) return 2 * set.colour_count;
    return 2 * set.colour[r] + (moves_second_side(set.rows[r]) ? 1u : 0u);
  };
  for (std::size_t r = 0; r < set.rows.size(); ++r) ++start[bucket_of(r) + 1];
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  set.order.resize(set.rows.size());
  for (std::size_t r = 0; r < set.rows.size(); ++r) set.order[start[bucket_of(r)]++] = static_cast<std::uint32_t>(r);
  // start[k] is now the end of bucket k.
  const ParticleBuffer<Scalar>& particles = state.particles;
  const auto fill_until = [&](std::size_t& next, std::size_t end) {
    for (; next < end; ++next) fill_slot(batches, batches.push(null_particle), set.rows[set.order[next]], set.order[next], particles);
  };
  std::size_t next = 0;
  for (std::uint32_t colour = 0; colour < set.colour_count; ++colour) {
    fill_until(next, start[2 * colour]);
    const std::size_t pairs = batches.slot_count();
    fill_until(next, start[2 * colour + 1]);
    batches.close_colour(null_particle, pairs);
  }
  fill_until(next, start[2 * set.colour_count]);  // the overflow; the trees' rows are left out
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
