// The particle method's contacts between limbs and with static geometry, as contact rows in the
// coloured sweeps (kernel/particles/contact_rows.hpp). Each test asserts a physical property:
// no interpenetration past a stated depth, Coulomb's law at the cone, the same bits for one or
// two threads and for scalar or SIMD lanes, nothing paid by a scene without collision.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/relaxation/contact_relaxation.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

Body capsule(std::string name, const Vector3& position, const Vector3& axis, double length = 0.4, double radius = 0.03,
             double mass = 1) {
  Body body;
  body.name = std::move(name);
  body.shape = {ShapeType::capsule, length, radius};
  body.mass = mass;
  body.position = position;
  body.axis = axis.normalized();
  return body;
}

Model empty_world() {
  Model model;
  model.settings.time_step = 1.0 / 240;
  model.settings.sleep.enabled = false;
  model.ground = Ground{0, 0, 0.5};
  return model;
}

VerletOptions options_with(int iterations, int threads = 1, bool simd = true) {
  VerletOptions options;
  options.relaxation.iterations = iterations;
  options.threads = threads, options.simd = simd, options.parallel_minimum_slots = 16;
  return options;
}

template <typename Scalar>
Eigen::Vector3d centre(const VerletState<Scalar>& state, std::size_t body) {
  const std::uint32_t limb = state.body_limb[body];
  return 0.5 * (state.particles.position(state.limbs.head[limb]) + state.particles.position(state.limbs.tail[limb])).template cast<double>();
}

template <typename Scalar>
double deepest(VerletState<Scalar>& state) {
  std::vector<LimbSegment> segments;
  for (std::size_t body = 0; body < state.body_limb.size(); ++body) {
    const std::uint32_t limb = state.body_limb[body];
    segments.push_back({state.particles.position(state.limbs.head[limb]).template cast<double>(),
                        state.particles.position(state.limbs.tail[limb]).template cast<double>(), state.limbs.radius[limb]});
  }
  return -state.collisions.deepest_overlap(segments).separation;
}

TEST(LimbContacts, ACapsuleDroppedAcrossAnotherRestsOnTopOfIt) {
  Model model = empty_world();
  model.bodies.push_back(capsule("below", {0, 0, 0.03}, Vector3::UnitX()));
  model.bodies.push_back(capsule("above", {0, 0, 0.5}, Vector3::UnitY()));
  auto state = compile<double>(model, options_with(20));
  ASSERT_TRUE(state.collisions.active());
  double worst = 0;
  for (int s = 0; s < 480; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok);
    worst = std::max(worst, deepest(state));
  }
  // At rest on top: its axis one diameter above the lower one's, within 2 mm; never deeper than 5 mm.
  EXPECT_NEAR(centre(state, 1).z(), 0.03 + 0.06, 2e-3);
  EXPECT_LT(worst, 5e-3);
}

// A capsule lying on a ramp along its slope: with μ = 0.5 it stays below tan θ = 0.5 and
// slides above it (Coulomb's cone), whatever the sweep count.
double slide_on_ramp(double slope) {
  Model model = empty_world();
  model.ground.reset();
  const double angle = std::atan(slope);
  StaticCollider ramp;
  ramp.name = "ramp";
  ramp.type = ColliderType::box;
  ramp.half_extents = {2, 1, 0.1};
  ramp.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(angle, Vector3::UnitY()));  // surface falls towards +x
  ramp.friction = 0.5;
  model.colliders.push_back(ramp);
  const Vector3 normal = ramp.orientation * Vector3::UnitZ(), downhill = ramp.orientation * Vector3::UnitX();
  model.bodies.push_back(capsule("log", (0.1 + 0.03) * normal, downhill));
  auto state = compile<double>(model, options_with(20));
  const Vector3 start = centre(state, 0);
  for (int s = 0; s < 240; ++s) EXPECT_EQ(step(state).status, StepStatus::ok);
  return (centre(state, 0) - start).dot(downhill);
}

TEST(LimbContacts, CoulombsLawHoldsAtTheFrictionCone) {
  EXPECT_LT(std::abs(slide_on_ramp(0.4)), 2e-3) << "below the cone it sticks";
  // Above it, it accelerates at g (sin θ − μ cos θ): 0.45 m/s² at tan θ = 0.6, 0.22 m in 1 s.
  const double theta = std::atan(0.6);
  const double expected = 0.5 * 9.81 * (std::sin(theta) - 0.5 * std::cos(theta));
  EXPECT_NEAR(slide_on_ramp(0.6), expected, 0.3 * expected) << "above the cone it slides";
}

// Capsules rained into a box of static walls: a pile with hundreds of contacts.
Model rained_capsules(int count) {
  Model model = empty_world();
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int k = 0; k < count; ++k) {
    const Vector3 at(0.15 * unit(random), 0.15 * unit(random), 0.1 + 0.08 * k);  // clear of the walls
    model.bodies.push_back(capsule("c" + std::to_string(k), at, Vector3(unit(random), unit(random), 0.3 * unit(random))));
  }
  for (int side = 0; side < 4; ++side) {
    StaticCollider wall;
    wall.name = "wall" + std::to_string(side);
    wall.type = ColliderType::box;
    const double sign = side % 2 == 0 ? 1 : -1;
    wall.position = side < 2 ? Vector3(sign * 0.6, 0, 0.5) : Vector3(0, sign * 0.6, 0.5);
    wall.half_extents = side < 2 ? Vector3(0.1, 0.7, 0.5) : Vector3(0.7, 0.1, 0.5);
    model.colliders.push_back(wall);
  }
  return model;
}

template <typename Scalar>
std::vector<Scalar> pile_positions(const Model& model, int threads, bool simd) {
  auto state = compile<Scalar>(model, options_with(8, threads, simd));
  for (int s = 0; s < 240; ++s) EXPECT_EQ(step(state).status, StepStatus::ok);
  std::vector<Scalar> positions(state.particles.position_x.begin(), state.particles.position_x.end());
  positions.insert(positions.end(), state.particles.position_z.begin(), state.particles.position_z.end());
  return positions;
}

template <typename Scalar>
class ParticleContactRows : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ParticleContactRows, Scalars);

TYPED_TEST(ParticleContactRows, ContactsGiveTheSameBitsForOneOrTwoThreadsAndScalarOrSimd) {
  const Model model = rained_capsules(60);
  const auto one = pile_positions<TypeParam>(model, 1, true);
  EXPECT_EQ(one, pile_positions<TypeParam>(model, 2, true)) << "two threads";
  EXPECT_EQ(one, pile_positions<TypeParam>(model, 1, false)) << "scalar lanes";
}

// The batches hold, per slot, what the sweeps no longer gather: the shares w_k c_k, the
// effective mass 1/Σ w_k c_k² and the start point Σ c_k x*_k at the previous positions (the
// substep's start). Inside each colour, the blocks before pair_begin hold rows against static
// geometry alone (places 2 and 3 unused), which the sweep projects over two places; every row
// has one slot.
TEST(LimbContacts, TheBatchesHoldWhatTheSweepsNoLongerGather) {
  auto state = compile<double>(rained_capsules(60), options_with(8));
  for (int s = 0; s < 240; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  // Restitution has moved the previous positions since the last substep packed its rows: pack
  // them again from these.
  build_contact_batches(state);
  const ContactRowBatches<double>& batches = state.plan.contact_batches;
  const auto& p = state.particles;
  ASSERT_GT(state.contact_rows.rows.size(), 50u);
  std::vector<int> slots_of_row(state.contact_rows.rows.size(), 0);
  std::size_t statics = 0, pairs = 0;
  for (std::size_t colour = 0; colour < batches.colour_count(); ++colour) {
    const std::size_t begin = batches.colour_begin[colour], split = batches.pair_begin[colour], end = batches.colour_begin[colour + 1];
    ASSERT_TRUE(begin <= split && split <= end && split % ContactRowBatches<double>::kBlockLanes == 0) << "colour " << colour;
    for (std::size_t slot = begin; slot < end; ++slot) {
      if (batches.row[slot] == ~std::uint32_t{0}) continue;
      const ContactRow& row = state.contact_rows.rows[batches.row[slot]];
      ++slots_of_row[batches.row[slot]];
      const bool static_row = row.coefficient[2] == 0 && row.coefficient[3] == 0;
      if (slot < split) {
        EXPECT_TRUE(static_row) << "slot " << slot << " is projected over two places";
      }
      (static_row ? statics : pairs) += 1;
      double denominator = 0;
      Eigen::Vector3d start = Eigen::Vector3d::Zero();
      for (std::size_t k = 0; k < kContactRowParticles; ++k) {
        const std::uint32_t q = row.particle[k];
        EXPECT_EQ(batches.share[k][slot], p.inverse_mass[q] * row.coefficient[k]);
        denominator += p.inverse_mass[q] * row.coefficient[k] * row.coefficient[k];
        start += row.coefficient[k] * p.previous(q);
      }
      ASSERT_GT(denominator, 0);
      EXPECT_NEAR(batches.effective_mass[slot], 1 / denominator, 1e-12 / denominator);
      EXPECT_NEAR(batches.start_x[slot], start.x(), 1e-12);
      EXPECT_NEAR(batches.start_y[slot], start.y(), 1e-12);
      EXPECT_NEAR(batches.start_z[slot], start.z(), 1e-12);
    }
  }
  EXPECT_GT(statics, 0u);
  EXPECT_GT(pairs, 0u);
  EXPECT_EQ(batches.overflow_begin(), batches.slot_count()) << "no overflow expected here";
  for (std::size_t r = 0; r < slots_of_row.size(); ++r) EXPECT_EQ(slots_of_row[r], 1) << "row " << r;
}

TEST(LimbContacts, APileOfCapsulesDoesNotInterpenetrate) {
  auto state = compile<double>(rained_capsules(60), options_with(20));
  double worst = 0;
  for (int s = 0; s < 480; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok);
    worst = std::max(worst, deepest(state));
  }
  EXPECT_LT(worst, 0.01) << "deepest overlap in the run, m";
  for (std::size_t body = 0; body < state.body_limb.size(); ++body) {
    const Vector3 at = centre(state, body);
    EXPECT_LT(std::max(std::abs(at.x()), std::abs(at.y())), 0.5) << "body " << body << " left the box";
  }
}

TEST(LimbContacts, AChainWithoutCollidersPaysNothingForCollision) {
  Model model = empty_world();
  for (int k = 0; k < 8; ++k) {
    model.bodies.push_back(capsule("link" + std::to_string(k), {0.2 + 0.4 * k, 0, 1}, Vector3::UnitX()));
    model.bodies.back().collision = {2, ~2u};  // links never meet links (the generators' choice)
    if (k > 0) model.joints.push_back(spherical_joint("j" + std::to_string(k), k - 1, k, {0.2, 0, 0}, {-0.2, 0, 0}));
  }
  auto state = compile<double>(model, options_with(8));
  EXPECT_FALSE(state.collisions.active());
  for (int s = 0; s < 60; ++s) step(state);
  EXPECT_TRUE(state.contact_rows.empty());
  EXPECT_EQ(state.plan.contact_batches.slot_count(), 0u);
  EXPECT_EQ(state.limb_segments.capacity(), 0u) << "no collision scratch was allocated";
}


// --- Contacts under the rattle rule ---

// The thesis's 5-link chain (tools/scenes/chain.json: pinned, released from the horizontal, its
// own rattle settings with over-relaxation 1.5) at 128 substeps × 2 sweeps in frames of 1/60 s,
// with its links colliding with each other (`limb_contacts`: the Model's default filters, which
// the chain generator leaves out) and, if `ground` is given, the ground that high (m). Stepped
// one substep at a time, to see each substep's energy and contacts.
struct RattleChainRun {
  double start = 0, end = 0;       ///< energy, J
  double largest_rise = 0;         ///< max over t of E(t) − min_{s ≤ t} E(s), J
  double largest_gain = 0;         ///< the most any substep gained, J
  double largest_contact_gain = 0; ///< the most a substep with a contact gained, J
  long contact_substeps = 0;       ///< substeps whose report counts a contact
  double largest_gap = 0;          ///< the largest joint gap or link stretch at a substep's end, relative
  double sweeps = 0;               ///< position and velocity sweeps a substep, mean
};

RattleChainRun run_rattle_chain(bool limb_contacts, std::optional<double> ground, double seconds) {
  const Scene scene = testing::shipped_scene("chain.json");
  Model model = scene.model;
  if (limb_contacts) {
    for (Body& body : model.bodies) body.collision = CollisionFilter{};
  }
  if (ground) model.ground = Ground{*ground, 0, 0.5};
  VerletOptions options = testing::with_scene_settings(scene);
  options.relaxation.projection = ProjectionRule::rattle;
  options.relaxation.substeps = 1, options.relaxation.iterations = 2;
  constexpr int kSubsteps = 128;
  const double h = 1.0 / (60 * kSubsteps);
  VerletState<double> state = compile<double>(model, options);
  EXPECT_EQ(state.collisions.active(), limb_contacts);
  RattleChainRun run;
  run.start = run.end = observe(state).energy();
  double lowest = run.start;
  for (long k = 0; k < std::lround(seconds * 60) * kSubsteps; ++k) {
    const StepReport report = step(state, h);
    EXPECT_EQ(report.status, StepStatus::ok);
    const Observation observation = observe(state);
    const double energy = observation.energy(), gain = energy - run.end;
    run.largest_gap = std::max({run.largest_gap, observation.max_joint_gap, observation.max_link_stretch});
    run.largest_gain = std::max(run.largest_gain, gain);
    if (report.contacts > 0) {
      run.contact_substeps += 1;
      run.largest_contact_gain = std::max(run.largest_contact_gain, gain);
    }
    run.largest_rise = std::max(run.largest_rise, energy - lowest);
    lowest = std::min(lowest, energy);
    run.end = energy;
  }
  run.sweeps = double(state.counters.constraint_projections) / double(state.plan.awake_constraints) / (seconds * 60 * kSubsteps);
  std::printf("[ rattle   ] limb contacts %s, ground %s: E %.3f -> %.3f J; largest rise %.3g J, largest substep gain %.3g J, "
              "with a contact %.3g J (%ld substeps); largest joint gap or stretch %.2g; sweeps a substep %.3f\n", limb_contacts ? "on" : "off", ground ? "yes" : "no",
              run.start, run.end, run.largest_rise, run.largest_gain, run.largest_contact_gain, run.contact_substeps, run.largest_gap,
              run.sweeps);
  return run;
}

// Contacts of restitution 0 with friction can only take energy. What a rattle run with two
// sweeps a substep may gain is what its unconverged sweeps store in the joints (gaps, and the
// rates that open them) and give back a few substeps later — the run without contacts measures
// that. So: no substep in which limbs touch gains more than the most any substep gains without
// contacts, and the largest rise of the energy is within twice the contact-free run's (the two
// trajectories part after the first contact, so their whips differ; twice is their margin).
TEST(RattleContacts, AChainFoldingOntoItselfGainsNoEnergyAtItsContacts) {
  const RattleChainRun free = run_rattle_chain(false, std::nullopt, 10);
  const RattleChainRun folding = run_rattle_chain(true, std::nullopt, 10);
  ASSERT_GT(folding.contact_substeps, 100) << "the links must meet";
  EXPECT_LT(folding.end, folding.start - 1) << "inelastic contacts take energy";
  EXPECT_LT(folding.largest_contact_gain, free.largest_gain);
  EXPECT_LT(folding.largest_rise, 2 * free.largest_rise);
}

// The same for the ground (plane contacts): the chain swings into it half a metre below its pin.
TEST(RattleContacts, AChainSwingingIntoTheGroundGainsNoEnergyThere) {
  const RattleChainRun free = run_rattle_chain(false, std::nullopt, 3);
  const RattleChainRun grounded = run_rattle_chain(false, 1.0, 3);
  ASSERT_GT(grounded.contact_substeps, 100) << "the chain must reach the ground";
  EXPECT_LT(grounded.largest_contact_gain, free.largest_gain);
  EXPECT_LT(grounded.largest_rise, 2 * free.largest_rise);
}

// Capsules dropped at different heights onto a static plate that bounces them (restitution 0.8)
// and onto each other: contacts come and go inside a frame.
Model bouncing_capsules() {
  Model model = empty_world();
  model.ground.reset();
  StaticCollider plate;
  plate.name = "plate";
  plate.type = ColliderType::box;
  plate.half_extents = {1, 1, 0.05};
  plate.restitution = 0.8;
  model.colliders.push_back(plate);
  for (int k = 0; k < 4; ++k) {
    const Vector3 axis(std::cos(0.7 * k), std::sin(0.7 * k), 0.2 * (k % 2));
    model.bodies.push_back(capsule("c" + std::to_string(k), {0.05 * k, 0.03 * k, 0.15 + 0.13 * k}, axis));
  }
  return model;
}

// A step of n substeps reports the most contacts any of its substeps had (StepReport::contacts),
// as the same run stepped one substep at a time — the same bits — reports them substep by
// substep; so a contact made and lost inside a frame is counted.
TEST(RattleContacts, AStepReportsTheMostContactsOfAnyOfItsSubsteps) {
  constexpr int kSubsteps = 16;
  VerletOptions options = options_with(2);
  options.relaxation.projection = ProjectionRule::rattle;
  options.relaxation.substeps = kSubsteps;
  auto framed = compile<double>(bouncing_capsules(), options);
  options.relaxation.substeps = 1;
  auto single = compile<double>(bouncing_capsules(), options);
  const double dt = 1.0 / 60;
  int early_only = 0, busier_before_the_end = 0, frames_with_contacts = 0;
  for (int frame = 0; frame < 90; ++frame) {
    const StepReport report = step(framed, dt);
    ASSERT_EQ(report.status, StepStatus::ok);
    int most = 0, last = 0;
    for (int k = 0; k < kSubsteps; ++k) {
      last = step(single, dt / kSubsteps).contacts;
      most = std::max(most, last);
    }
    ASSERT_EQ(framed.particles.position_x, single.particles.position_x) << "frame " << frame;
    EXPECT_EQ(report.contacts, most) << "frame " << frame;
    frames_with_contacts += most > 0 ? 1 : 0;
    early_only += most > 0 && last == 0 ? 1 : 0;
    busier_before_the_end += most > last ? 1 : 0;
  }
  EXPECT_GT(frames_with_contacts, 10);
  EXPECT_GT(early_only, 0) << "no frame had its only contacts before its last substep";
  EXPECT_GT(busier_before_the_end, early_only) << "no frame had more contacts in an earlier substep than in its last";
}

}  // namespace
}  // namespace limber
