// The `pbd` projection rule is the thesis's and Jakobsen's, and it must stay bit for bit what it
// was before the `rattle` rule and substeps were added. This is a change detector (as Jolt's
// determinism hash is): the fingerprints below were taken from the code before that change, on
// the shipped scenes and a chain, for each solver and both precisions. A change that alters any
// bit of a pbd trajectory fails here; if such a change is intended, say so and take new prints.
#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::load_shipped_scene;
using testing::make_chain;

// FNV-1a of the positions and previous positions of every live particle (the pbd state).
template <typename Scalar>
std::uint64_t state_print(const VerletState<Scalar>& state) {
  const auto& p = state.particles;
  std::uint64_t hash = 14695981039346656037ull;
  for (const auto* array : {&p.position_x, &p.position_y, &p.position_z, &p.previous_x, &p.previous_y, &p.previous_z}) {
    hash = fnv1a(array->data(), p.size() * sizeof(Scalar), hash);
  }
  return hash;
}

template <typename Scalar>
std::uint64_t run_print(const Model& model, const VerletOptions& options, int steps) {
  VerletState<Scalar> state = compile<Scalar>(model, options);
  for (int s = 0; s < steps; ++s) step(state);
  return state_print(state);
}

struct Case {
  const char* name;
  Model model;
  VerletOptions options;
  int steps;
  std::uint64_t float_print, double_print;  // taken before the rattle rule existed
};

// The relaxation settings the prints were taken with: the pbd rule, one step, 100 sweeps (the
// chain over-relaxed by 1.5), whatever the scene files now choose; the rods 7 sweeps.
VerletOptions with_relaxation(VerletOptions options, RelaxationSettings relaxation) {
  options.relaxation = relaxation;
  return options;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  const Model humanoid = load_shipped_scene("humanoid.json");
  const Model chain = load_shipped_scene("chain.json");
  Model rods = make_chain({1, 1, 2, 1, 3}, 0.2, true);
  rods.ground = Ground{0.5, 0.3, 0.4};
  VerletOptions gauss_seidel, jacobi, direct, sequential, unweighted, attachments;
  jacobi.solver = RelaxationSolver::jacobi;
  direct.solver = RelaxationSolver::direct;
  sequential.order = SweepOrder::sequential;
  unweighted.rule = RelaxationRule::unweighted;
  attachments.long_range_attachments = true;
  const RelaxationSettings thesis = testing::thesis_relaxation(100, 1.0), over = testing::thesis_relaxation(100, 1.5);
  VerletOptions rods_options = with_relaxation(gauss_seidel, testing::thesis_relaxation(7, 1.0));
  rods_options.verlet.limb_masses = LimbMasses::inertia;
  out.push_back({"humanoid gauss-seidel", humanoid, with_relaxation(gauss_seidel, thesis), 400, 0x12081e55ebefbc8dull, 0x2fb32d49679b29e6ull});
  out.push_back({"humanoid jacobi", humanoid, with_relaxation(jacobi, thesis), 400, 0x5c268cd0f4bfc9b0ull, 0xcb4474e5ff78731bull});
  // Retaken when the tree elimination's block products became loops written once for numbers
  // and SIMD lanes (a change of rounding order only: `limber run tools/scenes/humanoid.json
  // --solver direct --steps 600` prints the same gaps and energies to its last digit), and
  // again when the direct solver moved to constraint space (numerics/constraint_elimination.hpp):
  // over 600 steps, double gives the particle blocks' largest gap, stretch and energy to ten
  // digits; float the same largest gap and stretch to 0.1 % and the energy to 3e-5 (its own
  // rounding). Float's print was retaken once more when the front's coupling n_p·n_q became a sum
  // in a fixed order, (x + y) + z, for numbers and lanes alike (Eigen's float dot sums
  // x + (y + z)): double's is unchanged.
  // The particle blocks, still used for busier particles, keep the earlier prints
  // (0x8c61979a6e6ee27f, 0xf6c799529bcfc513) when a test forces them.
  out.push_back({"humanoid direct", humanoid, with_relaxation(direct, thesis), 400, 0xadf05baaa6666153ull, 0x9ff4a773249c3080ull});
  out.push_back({"chain gauss-seidel", chain, with_relaxation(gauss_seidel, over), 300, 0x737203bc81c5e931ull, 0x9d3e370e8ed86d0eull});
  out.push_back({"chain sequential", chain, with_relaxation(sequential, over), 300, 0xf20cc64821cfa54dull, 0x010f797ece2253e1ull});
  out.push_back({"chain unweighted", chain, with_relaxation(unweighted, over), 300, 0x460cecf72a8fe9dfull, 0x3fdeccdc17c528c1ull});
  out.push_back({"chain long-range attachments", chain, with_relaxation(attachments, over), 300, 0xbb49797b0adf3b21ull, 0x5b5ec05c8e59a2f1ull});
  out.push_back({"three-particle rods on the ground", rods, rods_options, 500, 0xd209f090862df593ull, 0xf79aedf27bae2230ull});
  return out;
}

TEST(PbdBits, EveryPbdPathKeepsItsBitsFromBeforeRattle) {
  for (const Case& c : cases()) {
    EXPECT_EQ(run_print<float>(c.model, c.options, c.steps), c.float_print) << "float " << c.name;
    EXPECT_EQ(run_print<double>(c.model, c.options, c.steps), c.double_print) << "double " << c.name;
  }
}

}  // namespace
}  // namespace limber
