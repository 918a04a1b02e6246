// The Featherstone method's contact solve (kernel/featherstone/joint_space_contacts.hpp,
// "Impulses"): projected Gauss–Seidel on the contacts' rows through the joint-space factor, warm
// started from the last step's impulses. Its answer, converged, is the Signorini–Coulomb one —
// each contact pushes only while it touches, reaches its target speed while it pushes, and its
// friction stops its slip inside the cone or opposes it on the cone's edge — read from the
// velocities forward kinematics gives, not from the solver's own bookkeeping; and a resting scene's
// warm start begins at its answer.

#pragma GCC diagnostic ignored "-Warray-bounds"  // GCC 12 false positives in Eigen's AVX-512 reductions
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/collision/rigid_contacts.hpp"
#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/numerics/contact_projection.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::load_shipped_scene;

// The relative velocity of contact c's two material points (a's less b's, world, m/s) from the
// body velocities in `motion` (forward_kinematics of the state's q and v).
Eigen::Vector3d contact_velocity(const FeatherstoneState& state, const DynamicsWorkspace& motion, const RigidContact& contact) {
  const auto point_velocity = [&](std::int32_t scene_body) -> Eigen::Vector3d {
    if (scene_body < 0) return Eigen::Vector3d::Zero();
    const auto i = static_cast<std::size_t>(state.tree_body[static_cast<std::size_t>(scene_body)]);
    const PluckerTransform& world_to_body = motion.world_to_body[i];
    const Eigen::Matrix3d to_world = world_to_body.rotation.transpose();
    const Eigen::Vector3d omega = to_world * motion.velocity[i].head<3>(), origin = to_world * motion.velocity[i].tail<3>();
    return origin + omega.cross(contact.point - world_to_body.translation);
  };
  return point_velocity(contact.a) - point_velocity(contact.b);
}

// Each contact's impulse (its frame: normal, t₁, t₂; N·s) as the solver left it.
std::vector<Eigen::Vector3d> contact_impulses(const FeatherstoneState& state) {
  const JointSpaceContactScratch& s = state.contact;
  std::vector<Eigen::Vector3d> impulses(state.contacts.size(), Eigen::Vector3d::Zero());
  for (const ConstraintGroup& group : s.groups) {
    for (int g = group.first_block; g < group.first_row_block; ++g) {
      impulses[static_cast<std::size_t>(s.block_source[static_cast<std::size_t>(g)])] = s.impulse[static_cast<std::size_t>(g)];
    }
  }
  return impulses;
}

// How far the step's contacts are from Signorini's and Coulomb's conditions, m/s: the largest
// approach past a contact's target, the largest miss of the target by a contact that pushes, and
// the largest slip of a contact stuck inside its cone or not opposed by its friction on the edge.
struct ConditionMiss {
  double approach = 0, pushing = 0, slip = 0;
  int contacts = 0, sticking = 0, sliding = 0;
};

void measure_conditions(const FeatherstoneState& state, double dt, ConditionMiss& miss) {
  DynamicsWorkspace motion;
  forward_kinematics(state.tree, state.q, state.v, motion);
  const std::vector<Eigen::Vector3d> impulses = contact_impulses(state);
  for (std::size_t c = 0; c < state.contacts.size(); ++c) {
    const RigidContact& contact = state.contacts[c];
    const Eigen::Vector3d u = contact_frame(contact.normal) * contact_velocity(state, motion, contact);
    const Eigen::Vector3d& impulse = impulses[c];
    // The target the rule sets: a bounce leaves at e times its approach, a contact apart by a gap
    // may close it in the step.
    const double target = contact_target_speed(contact, /*before_move=*/true, dt);
    ++miss.contacts;
    miss.approach = std::max(miss.approach, target - u[0]);
    if (!(impulse[0] > 0)) continue;
    miss.pushing = std::max(miss.pushing, std::abs(u[0] - target));
    if (!(contact.friction > 0)) continue;
    const double tangential = impulse.tail<2>().norm(), bound = contact.friction * impulse[0], slip = u.tail<2>().norm();
    if (tangential < bound * (1 - 1e-6)) {
      ++miss.sticking;
      miss.slip = std::max(miss.slip, slip);
    } else if (slip > 0) {
      ++miss.sliding;
      // Maximal dissipation: the friction impulse against the slip it leaves.
      miss.slip = std::max(miss.slip, (u.tail<2>() + slip * impulse.tail<2>() / std::max(tangential, 1e-300)).norm());
    }
  }
}

TEST(FeatherstoneContactSolve, ConvergedImpulsesMeetSignoriniAndCoulomb) {
  // humanoid.json knocked by the ball, a thrown chain on rough bouncy ground and the ragdoll
  // pile (limbs on limbs), under semi-implicit Euler (contacts before the move, speculative gaps)
  // for 0.5 s (the chain at 1/960 s: semi-implicit Euler's explicit gyroscopic terms wind it up
  // at 1/240 s), the passes allowed to converge: after every step's solve, the velocities forward
  // kinematics gives meet the contact conditions to 10⁻⁴ m/s (the passes end once no impulse
  // would change a speed by 10⁻⁶ m/s). Clamping the stopping friction impulse to the disc
  // instead of minimizing within it missed maximal dissipation by up to 1.5 m/s (the chain).
  // (Sequential impulses that only push, this solver's predecessor, left pushing contacts
  // separating and friction slipping inside its cone.)
  Model chain = make_chain_model({.links = 5, .link_length = 0.2, .link_mass = 1, .anchor = Vector3(0, 0, 0.6),
                                  .direction = Vector3(1, 0.3, -0.4), .pinned = false});
  for (Body& body : chain.bodies) body.shape.radius = 0.02;
  chain.ground = Ground{0, 0.4, 0.8};
  chain.settings.time_step = 1.0 / 960;
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (Body& body : chain.bodies) {
    body.angular_velocity = 4 * Vector3(unit(random), unit(random), unit(random));
    body.linear_velocity = Vector3(1, 0, -2) + Vector3(unit(random), unit(random), unit(random));
  }
  Model humanoid = load_shipped_scene("humanoid.json"), pile = load_shipped_scene("ragdoll_pile.json");
  for (Model* model : {&humanoid, &chain, &pile}) {
    model->settings.sleep.enabled = false;
    FeatherstoneState state = compile_featherstone(*model, {.integrator = Integrator::semi_implicit_euler});
    state.contact_iterations = 2000;
    const double dt = model->settings.time_step;
    ConditionMiss miss;
    for (int s = 0; s < std::lround(0.5 / dt); ++s) {
      state.speculative_time = dt;
      if (detect_rigid_contacts(state)) take_moved_balls(state);
      remember_step_start(state);
      integrate_awake_islands(state, dt);
      resolve_joint_space_contacts(state, dt);
      measure_conditions(state, dt, miss);
      for (const std::int32_t k : state.awake_islands) advance_positions(state, static_cast<std::size_t>(k));
      state.time += dt;
      ASSERT_EQ(update_sleep(state, dt), StepStatus::ok) << model->name << " at " << s;
    }
    EXPECT_GT(miss.sticking + miss.sliding, 50) << model->name;
    EXPECT_LT(miss.approach, 1e-4) << model->name;
    EXPECT_LT(miss.pushing, 1e-4) << model->name;
    EXPECT_LT(miss.slip, 1e-4) << model->name;
    RecordProperty(model->name, std::to_string(miss.contacts) + " contacts (" + std::to_string(miss.sticking) + " sticking, " +
                                    std::to_string(miss.sliding) + " sliding): approach " + std::to_string(miss.approach) + ", pushing " +
                                    std::to_string(miss.pushing) + ", slip " + std::to_string(miss.slip) + " m/s");
  }
}

TEST(FeatherstoneContactSolve, ARestingScenesWarmStartBeginsAtItsAnswer) {
  // The humanoid lying on the ground after 3 s: one pass from the last step's impulses leaves the
  // velocities within 1 % of the converged answer's change to them (kinetic-energy norm), where
  // one pass from none misses by a tenth or more.
  Model model = load_shipped_scene("humanoid.json");
  model.settings.sleep.enabled = false;
  model.balls.clear();
  FeatherstoneState state = compile_featherstone(model, {.integrator = Integrator::semi_implicit_euler});
  const double dt = model.settings.time_step;
  for (int s = 0; s < std::lround(3.0 / dt); ++s) ASSERT_EQ(step(state, dt).status, StepStatus::ok);
  const auto after_one_step = [&](int passes, bool warm) {
    FeatherstoneState copy = state;
    copy.contact_iterations = passes;
    if (!warm) copy.contact.memory.clear(), copy.contact.remembered_rows.clear();
    EXPECT_EQ(step(copy, dt).status, StepStatus::ok);
    return copy.v;
  };
  const Eigen::VectorXd free = after_one_step(0, false), converged = after_one_step(2000, false);
  DynamicsWorkspace workspace;
  Eigen::MatrixXd inertia;
  mass_matrix(state.tree, state.q, workspace, inertia);
  const auto distance = [&](const Eigen::VectorXd& x) { return std::sqrt(x.dot(inertia * x)) / std::sqrt((converged - free).dot(inertia * (converged - free))); };
  const double warm = distance(after_one_step(1, true) - converged), cold = distance(after_one_step(1, false) - converged);
  EXPECT_LT(warm, 0.01);
  EXPECT_GT(cold, 0.1);
  RecordProperty("one_pass", "warm " + std::to_string(warm) + ", cold " + std::to_string(cold) + " of the converged change");
}

}  // namespace
}  // namespace limber
