// The collision world's set-up (kernel/geometry/limb_collisions.hpp) examines pairs in proportion
// to the bodies — per pair of distinct collision filters, and the sweep for overlaps at the
// Model's poses — never every pair of bodies: a long chain and a lattice of ragdolls load in
// time linear in their size.
#include <algorithm>
#include <cstdint>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

Model chain_of(std::size_t links, bool links_meet) {
  ChainSpec spec;
  spec.links = links;
  Model model = make_chain_model(spec);
  if (links_meet) {
    for (Body& body : model.bodies) body.collision = CollisionFilter{};
  }
  return model;
}

TEST(LimbCollisionsSetUp, ExaminesPairsInProportionToAChainsLinks) {
  // The generators' links never meet (one filter that leaves itself out): every pair of 4·10⁴
  // links would be 8·10⁸ checks. Links that may meet: the sweep along the chain, about two
  // neighbours a link.
  for (const bool links_meet : {false, true}) {
    const LimbCollisions chain(chain_of(10'000, links_meet)), chain_4x(chain_of(40'000, links_meet));
    EXPECT_EQ(chain.active(), links_meet);
    EXPECT_LT(chain_4x.set_up_comparisons(), 5 * std::max<std::uint64_t>(chain.set_up_comparisons(), 1))
        << chain.set_up_comparisons() << " then " << chain_4x.set_up_comparisons() << ", links meet: " << links_meet;
  }
}

TEST(LimbCollisionsSetUp, ExaminesPairsInProportionToALatticeOfRagdolls) {
  // ragdoll.json's limbs meet each other: the sweep for limbs overlapping at the Model's poses
  // runs over every copy. Along one axis alone it would compare each limb with a whole column of
  // the lattice (8 times the work for 4 times the copies).
  const Model ragdoll = testing::load_shipped_scene("ragdoll.json");
  const double spacing = footprint(ragdoll) + 0.1;
  const LimbCollisions lattice(copies_of(ragdoll, 100, spacing, "r", "copies"));
  const LimbCollisions lattice_4x(copies_of(ragdoll, 400, spacing, "r", "copies"));
  ASSERT_TRUE(lattice.active());
  EXPECT_GT(lattice.set_up_comparisons(), 0u);
  EXPECT_LT(lattice_4x.set_up_comparisons(), 5 * lattice.set_up_comparisons())
      << lattice.set_up_comparisons() << " then " << lattice_4x.set_up_comparisons();
}

}  // namespace
}  // namespace limber
