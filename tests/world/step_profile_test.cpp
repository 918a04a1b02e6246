// StepReport::profile (model/step_status.hpp): off, it is all zeros; on, the stages' times
// partition the step and its counts are the report's; on or off, the trajectory is the same bits.
// No timing beyond those inequalities: speed is measured in bench/ragdolls.md.
#include <cstring>
#include <string>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// A scene under a method, as the command line would set it up (the scene's method settings).
struct Case {
  std::string name;
  Scene scene;
  WorldOptions options;
};

std::vector<Case> particle_cases() {
  const Scene pile = testing::shipped_scene("ragdoll_pile.json");
  const Scene humanoid = testing::shipped_scene("humanoid.json");
  std::vector<Case> cases;
  // 32 ragdolls landing on stairs by step 50: limb–limb and limb–mesh rows, coloured and swept.
  cases.push_back({"pile, the scene's settings", pile, world_options(Method::particles, pile.methods)});
  // Rattle in 4 substeps: the velocity stage, its sweeps, a float state.
  Case rattle{"humanoid, rattle in 4 substeps, float", humanoid, world_options(Method::particles, humanoid.methods)};
  rattle.options.particles.relaxation.projection = ProjectionRule::rattle;
  rattle.options.particles.relaxation.substeps = 4;
  rattle.options.single_precision = true;
  cases.push_back(rattle);
  return cases;
}

std::vector<Case> rigid_cases() {
  const Scene humanoid = testing::shipped_scene("humanoid.json");
  std::vector<Case> cases;
  Case springs{"humanoid, implicit springs", humanoid, world_options(Method::springs, humanoid.methods)};
  springs.options.springs.integrator = Integrator::backward_euler;
  cases.push_back(springs);
  cases.push_back({"humanoid, lagrange", humanoid, world_options(Method::lagrange, humanoid.methods)});
  cases.push_back({"humanoid, featherstone", humanoid, world_options(Method::featherstone, humanoid.methods)});
  return cases;
}

void set_profile(WorldOptions& options, bool on) {
  options.particles.profile = options.springs.profile = options.lagrange.profile = options.featherstone.profile = on;
}

StepReport step_any(MethodState& state, double dt) {
  return std::visit([&](auto& s) { return step(s, dt); }, state);
}

// Every position coordinate of the state (particles, or bodies' centres and orientations).
std::vector<double> positions(const MethodState& state) {
  std::vector<double> out;
  std::visit(
      [&](const auto& s) {
        if constexpr (requires { s.particles; }) {
          for (std::uint32_t i = 0; i < s.particles.size(); ++i) {
            for (int axis = 0; axis < 3; ++axis) out.push_back(double(s.particles.position(i)[axis]));
          }
        } else {
          for (const Eigen::Vector3d& x : s.bodies.state.position) out.insert(out.end(), x.data(), x.data() + 3);
          for (const Eigen::Quaterniond& q : s.bodies.state.orientation) out.insert(out.end(), q.coeffs().data(), q.coeffs().data() + 4);
        }
      },
      state);
  return out;
}

// Runs `steps` steps with the profile on or off, calling `check(report)` after each.
template <typename Check>
std::vector<double> run(Case c, bool profile, int steps, Check&& check) {
  set_profile(c.options, profile);
  MethodState state = compile_method(c.scene.model, c.options);
  for (int s = 0; s < steps; ++s) {
    const StepReport report = step_any(state, c.scene.model.settings.time_step);
    EXPECT_EQ(report.status, StepStatus::ok) << c.name << ", step " << s;
    check(report);
  }
  return positions(state);
}

double stages(const StepProfile& p) {
  return p.integrate + p.detect + p.colour + p.relax + p.velocity + p.restitution + p.sleep;
}

bool all_zero(const StepProfile& p) {
  return p.integrate == 0 && p.detect == 0 && p.colour == 0 && p.relax == 0 && p.velocity == 0 && p.restitution == 0 &&
         p.sleep == 0 && p.step == 0 && p.substeps == 0 && p.position_sweeps == 0 && p.velocity_sweeps == 0 &&
         p.contact_rows == 0 && p.contact_colours == 0 && p.candidate_pairs == 0 && p.limb_searches == 0 && p.contacts == 0;
}

// The stages are laps of one clock inside the step's own: their sum can pass the step's time only
// by the rounding of the laps' conversions to seconds.
constexpr double kClockSlack = 1e-9;  // s

TEST(StepProfile, TimingTheStagesChangesNoBitOfTheTrajectory) {
  std::vector<Case> cases = particle_cases();
  for (Case& c : rigid_cases()) cases.push_back(c);
  for (const Case& c : cases) {
    const std::vector<double> off = run(c, false, 50, [](const StepReport&) {});
    const std::vector<double> on = run(c, true, 50, [](const StepReport&) {});
    ASSERT_EQ(off.size(), on.size()) << c.name;
    EXPECT_EQ(std::memcmp(off.data(), on.data(), off.size() * sizeof(double)), 0) << c.name;
  }
}

TEST(StepProfile, IsAllZerosUnlessTheOptionsAskForIt) {
  std::vector<Case> cases = particle_cases();
  for (Case& c : rigid_cases()) cases.push_back(c);
  for (const Case& c : cases) {
    run(c, false, 50, [&](const StepReport& report) { EXPECT_TRUE(all_zero(report.profile)) << c.name; });
  }
}

TEST(StepProfile, ParticleStagesPartitionTheStepAndCountWhatTheReportCounts) {
  for (const Case& c : particle_cases()) {
    const bool rattle = c.options.particles.relaxation.projection == ProjectionRule::rattle;
    int candidate_pairs = 0, contact_rows = 0, contact_colours = 0;
    run(c, true, 50, [&](const StepReport& report) {
      const StepProfile& p = report.profile;
      for (double stage : {p.integrate, p.detect, p.colour, p.relax, p.velocity, p.restitution, p.sleep}) EXPECT_GE(stage, 0) << c.name;
      EXPECT_GT(p.step, 0) << c.name;
      EXPECT_LE(stages(p), p.step + kClockSlack) << c.name;
      EXPECT_EQ(p.substeps, report.substeps) << c.name;
      EXPECT_EQ(p.position_sweeps, report.iterations) << c.name;
      // The report keeps the most contacts in a substep, the profile their sum.
      EXPECT_GE(p.contacts, report.contacts) << c.name;
      EXPECT_LE(p.contacts, report.substeps * report.contacts) << c.name;
      // Rattle: at least one velocity sweep a substep, restitution inside them; pbd has neither.
      if (rattle) {
        EXPECT_GE(p.velocity_sweeps, p.substeps) << c.name;
        EXPECT_EQ(p.restitution, 0) << c.name;
      } else {
        EXPECT_EQ(p.velocity_sweeps, 0) << c.name;
      }
      // Rows come in at least one colour, and no more colours than rows — unless the joint
      // trees take them all (tree_contacts.hpp: rows between tree limbs are in no colour).
      EXPECT_LE(p.contact_colours, p.contact_rows) << c.name;
      if (p.contact_rows > 0 && c.options.particles.verlet.joint_solve != JointSolve::tree) {
        EXPECT_GE(p.contact_colours, 1) << c.name;
      }
      candidate_pairs += p.candidate_pairs, contact_rows += p.contact_rows, contact_colours += p.contact_colours;
    });
    if (c.scene.model.name == "ragdoll_pile") {  // the pile has landed by step 50
      EXPECT_GT(candidate_pairs, 0);
      EXPECT_GT(contact_rows, 0);
    }
  }
}

// The broadphase runs at a step's first substep; the others run the narrowphase on its pairs
// unless a limb outran them or an island woke or slept (kernel/collision/limb_contacts.hpp).
TEST(StepProfile, AStepOfSubstepsSearchesTheBroadphaseAboutOnce) {
  Case c = particle_cases().front();  // the pile, landing on the stairs and on one another
  ASSERT_EQ(c.scene.model.name, "ragdoll_pile");
  constexpr int kSubsteps = 4, kSteps = 60;
  c.options.particles.relaxation.substeps = kSubsteps;
  c.options.particles.relaxation.iterations = 4;
  int searches = 0, candidate_pairs = 0;
  run(c, true, kSteps, [&](const StepReport& report) {
    const StepProfile& p = report.profile;
    EXPECT_GE(p.limb_searches, 1);  // every step's first substep
    EXPECT_LE(p.limb_searches, kSubsteps);
    searches += p.limb_searches, candidate_pairs += p.candidate_pairs;
  });
  EXPECT_GT(candidate_pairs, 0);
  EXPECT_LT(searches, kSteps * 3 / 2);  // a search a substep would be 4 a step
}

TEST(StepProfile, RigidMethodsTimeTheStepTheirIntegratorAndDetection) {
  for (const Case& c : rigid_cases()) {
    run(c, true, 50, [&](const StepReport& report) {
      const StepProfile& p = report.profile;
      EXPECT_GT(p.step, 0) << c.name;
      EXPECT_GE(p.integrate, 0) << c.name;
      EXPECT_GE(p.detect, 0) << c.name;
      EXPECT_LE(p.integrate + p.detect, p.step + kClockSlack) << c.name;
      EXPECT_EQ(p.substeps, 1) << c.name;
      EXPECT_EQ(p.contacts, report.contacts) << c.name;
      // The stages they do not have stay 0.
      EXPECT_EQ(p.colour + p.relax + p.velocity + p.restitution + p.sleep, 0) << c.name;
      EXPECT_EQ(p.position_sweeps + p.velocity_sweeps + p.contact_rows + p.contact_colours, 0) << c.name;
    });
  }
}

}  // namespace
}  // namespace limber
