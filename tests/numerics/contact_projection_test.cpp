// The contact step of projected Gauss–Seidel (kernel/numerics/contact_projection.hpp): the
// friction impulse within Coulomb's disc is the minimum of the tangential rows' energy (its
// Karush–Kuhn–Tucker conditions, and no point of the disc lower), and passes of the step over
// several coupled contacts, on random Delassus matrices J H⁻¹ Jᵀ, converge to the
// Signorini–Coulomb conditions: no contact pulls or leaves its cone, none approaches past its
// target, one that pushes meets it, its friction stops its slip inside the cone and opposes it on
// the edge.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>


#include "limber/kernel/numerics/contact_projection.hpp"
#include "tests/support/delassus.hpp"

namespace limber {
namespace {

using testing::random_delassus;

double tangential_energy(const Eigen::Matrix2d& a, const Eigen::Vector2d& g, const Eigen::Vector2d& x) { return 0.5 * x.dot(a * x) + g.dot(x); }

TEST(ContactProjection, TheFrictionImpulseIsTheDiscsLowestEnergy) {
  // Random 2×2 tangent blocks (some nearly singular), slips and radii: the answer lies in the
  // disc; inside it the gradient Aλ + g vanishes; on its edge the gradient is −μ'λ with μ' ≥ 0
  // (so the slip left opposes the impulse); and no point sampled on or in the disc has lower
  // energy.
  std::mt19937 random(11);
  std::uniform_real_distribution<double> draw(-1, 1), positive(0, 1);
  int on_edge = 0, inside = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::MatrixXd block = random_delassus(random, 2, trial % 5 == 0 ? 1 : 3, 0.1);
    const Eigen::Matrix2d a = block;
    const Eigen::Vector2d g(draw(random), draw(random));
    const double radius = positive(random);
    const Eigen::Vector2d x = disc_minimum(a(0, 0), a(0, 1), a(1, 1), g, radius);
    ASSERT_LE(x.norm(), radius * (1 + 1e-12)) << trial;
    const Eigen::Vector2d gradient = a * x + g;
    if (x.norm() < radius * (1 - 1e-9)) {
      ++inside;
      EXPECT_LT(gradient.norm(), 1e-9 * (1 + g.norm())) << trial;
    } else {
      ++on_edge;
      // gradient = −μ'x: parallel to x, against it.
      EXPECT_LT(std::abs(gradient.x() * x.y() - gradient.y() * x.x()), 1e-7 * (1 + gradient.norm()) * radius) << trial;
      EXPECT_LE(gradient.dot(x), 1e-9 * (1 + gradient.norm()) * radius) << trial;
    }
    const double lowest = tangential_energy(a, g, x);
    for (int k = 0; k < 64; ++k) {
      const double angle = 2 * std::numbers::pi * k / 64, r = radius * std::sqrt(positive(random));
      for (const double distance : {r, radius}) {
        EXPECT_GE(tangential_energy(a, g, distance * Eigen::Vector2d(std::cos(angle), std::sin(angle))), lowest - 1e-12) << trial;
      }
    }
  }
  EXPECT_GT(on_edge, 200);
  EXPECT_GT(inside, 200);
}

TEST(ContactProjection, PassesOverCoupledContactsMeetSignoriniAndCoulomb) {
  // Four contacts (12 rows) on 9 coordinates — coupled, as a limb's contacts are through its
  // joints — with random speeds, targets and friction: 2000 passes of the step, each contact's
  // speed read from the Delassus matrix, then the conditions to 10⁻⁸ m/s.
  std::mt19937 random(3);
  std::uniform_real_distribution<double> draw(-1, 1), positive(0, 1);
  constexpr int kContacts = 4, kRows = 3 * kContacts;
  int sticking = 0, sliding = 0, apart = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::MatrixXd a = random_delassus(random, kRows, 9, 0.1);
    Eigen::VectorXd free(kRows), impulse = Eigen::VectorXd::Zero(kRows);
    for (int r = 0; r < kRows; ++r) free[r] = draw(random);
    Eigen::Vector<double, kContacts> target, friction;
    for (int c = 0; c < kContacts; ++c) target[c] = 0.2 * draw(random), friction[c] = positive(random);
    for (int pass = 0; pass < 2000; ++pass) {
      for (int c = 0; c < kContacts; ++c) {
        const Eigen::VectorXd speed = free + a * impulse;
        const Eigen::Matrix3d k = a.block<3, 3>(3 * c, 3 * c);
        impulse.segment<3>(3 * c) = project_contact_impulse(k, speed.segment<3>(3 * c), impulse.segment<3>(3 * c), target[c], friction[c]);
      }
    }
    const Eigen::VectorXd speed = free + a * impulse;
    for (int c = 0; c < kContacts; ++c) {
      const Eigen::Vector3d u = speed.segment<3>(3 * c), l = impulse.segment<3>(3 * c);
      EXPECT_GE(l[0], 0) << trial;
      EXPECT_LE(l.tail<2>().norm(), friction[c] * l[0] * (1 + 1e-12) + 1e-15) << trial;
      EXPECT_GE(u[0], target[c] - 1e-8) << trial;
      if (!(l[0] > 1e-12)) {
        ++apart;
        continue;
      }
      EXPECT_NEAR(u[0], target[c], 1e-8) << trial;
      if (l.tail<2>().norm() < friction[c] * l[0] * (1 - 1e-6)) {
        ++sticking;
        EXPECT_LT(u.tail<2>().norm(), 1e-8) << trial;
      } else {
        ++sliding;
        // Maximal dissipation: the slip is −s·λ_t, s ≥ 0.
        const Eigen::Vector2d slip = u.tail<2>(), force = l.tail<2>();
        EXPECT_LT(std::abs(slip.x() * force.y() - slip.y() * force.x()), 1e-8 * (1 + force.norm())) << trial;
        EXPECT_LE(slip.dot(force), 1e-8 * (1 + force.norm())) << trial;
      }
    }
  }
  EXPECT_GT(sticking, 20);
  EXPECT_GT(sliding, 50);
  EXPECT_GT(apart, 50);
}

}  // namespace
}  // namespace limber
