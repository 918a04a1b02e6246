// Impulse response of colliding rigid bodies (thesis 2.5, eq. 2.32–2.37): conservation laws,
// Newton restitution, Coulomb friction, and the thesis's own formulas as special cases.
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "limber/kernel/collision/impulses.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

// A body with its mass and world inertia kept beside the inverses the impulse code reads, so
// momentum and energy can be measured independently of them.
struct FreeBody {
  ImpulseBody state;
  double mass = 0;
  Matrix3d inertia = Matrix3d::Zero();  // world frame, about the centre of mass
};

class Random {
 public:
  explicit Random(unsigned seed) : engine_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  Vector3d vector(double half_width) {
    return {uniform(-half_width, half_width), uniform(-half_width, half_width), uniform(-half_width, half_width)};
  }
  Vector3d unit() {
    std::normal_distribution<double> gauss;
    return Vector3d(gauss(engine_), gauss(engine_), gauss(engine_)).normalized();
  }
  Quaterniond rotation() {
    std::normal_distribution<double> gauss;
    return Quaterniond(gauss(engine_), gauss(engine_), gauss(engine_), gauss(engine_)).normalized();
  }
  // A free body: mass in [0.5, 5] kg, inertia a random rotation of a random positive diagonal.
  FreeBody body() {
    FreeBody b;
    b.mass = uniform(0.5, 5);
    const Vector3d moments(uniform(0.05, 2), uniform(0.05, 2), uniform(0.05, 2));
    const Quaterniond orientation = rotation();
    const Matrix3d r = orientation.toRotationMatrix();
    b.inertia = r * moments.asDiagonal() * r.transpose();
    b.state.inverse_mass = 1 / b.mass;
    b.state.inverse_inertia = world_inverse_inertia(Matrix3d(moments.asDiagonal()), orientation);
    b.state.centre_of_mass = vector(2);
    b.state.linear_velocity = vector(1);
    b.state.angular_velocity = vector(1);
    return b;
  }

 private:
  std::mt19937 engine_;
};

// Two free bodies meeting at a random point with a random normal, turned so that they approach.
struct Impact {
  FreeBody a, b;
  Vector3d point, normal;
};
Impact random_impact(Random& random) {
  Impact impact{random.body(), random.body(), random.vector(1), random.unit()};
  const Vector3d relative = velocity_at(impact.a.state, impact.point) - velocity_at(impact.b.state, impact.point);
  if (relative.dot(impact.normal) > 0) impact.normal = -impact.normal;
  return impact;
}

double kinetic_energy(const FreeBody& body) {
  const ImpulseBody& s = body.state;
  return 0.5 * body.mass * s.linear_velocity.squaredNorm() + 0.5 * s.angular_velocity.dot(body.inertia * s.angular_velocity);
}
double kinetic_energy(const Impact& impact) { return kinetic_energy(impact.a) + kinetic_energy(impact.b); }

Vector3d relative_velocity(const Impact& impact) {
  return velocity_at(impact.a.state, impact.point) - velocity_at(impact.b.state, impact.point);
}

// +j on a, −j on b at the contact point.
void apply(Impact& impact, const Vector3d& impulse) {
  apply_impulse(impact.a.state, impact.point, impulse);
  apply_impulse(impact.b.state, impact.point, -impulse);
}

// Immovable ground: the half-space below z = 0, normal +z towards the body above it.
ImpulseBody ground() { return ImpulseBody{}; }

TEST(ImpulseResponse, WorldInverseInertiaInvertsTheRotatedTensor) {
  Random random(11);
  for (int trial = 0; trial < 100; ++trial) {
    const FreeBody body = random.body();
    EXPECT_TRUE((body.inertia * body.state.inverse_inertia).isApprox(Matrix3d::Identity(), 1e-12));
    EXPECT_EQ(body.state.inverse_inertia, body.state.inverse_inertia.transpose());
  }
  EXPECT_THROW(world_inverse_inertia(Vector3d(1, 0, 1).asDiagonal().toDenseMatrix(), Quaterniond::Identity()),
               std::invalid_argument);
}

TEST(ImpulseResponse, CollisionMatrixMapsAnImpulseToTheChangeOfRelativeVelocity) {
  Random random(12);
  for (int trial = 0; trial < 100; ++trial) {
    Impact impact = random_impact(random);
    const Matrix3d k = collision_matrix(impact.a.state, impact.b.state, impact.point);
    const Vector3d before = relative_velocity(impact);
    const Vector3d impulse = random.vector(1);
    apply(impact, impulse);
    EXPECT_TRUE((relative_velocity(impact) - before).isApprox(k * impulse, 1e-12));
    EXPECT_TRUE(k.isApprox(k.transpose(), 1e-14));
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix3d>(k).eigenvalues().minCoeff(), 0);
  }
}

TEST(ImpulseResponse, NormalEntryOfCollisionMatrixIsTheThesisDenominator) {
  // Eq. 2.37: 1/m1 + 1/m2 + ((r1×n)×r1/I1 + (r2×n)×r2/I2)·n, with "/I" as the tensor's inverse.
  Random random(13);
  for (int trial = 0; trial < 100; ++trial) {
    const Impact impact = random_impact(random);
    const ImpulseBody& a = impact.a.state;
    const ImpulseBody& b = impact.b.state;
    const Vector3d& n = impact.normal;
    const Vector3d r1 = impact.point - a.centre_of_mass;
    const Vector3d r2 = impact.point - b.centre_of_mass;
    const double thesis = a.inverse_mass + b.inverse_mass +
                          ((a.inverse_inertia * r1.cross(n)).cross(r1) + (b.inverse_inertia * r2.cross(n)).cross(r2)).dot(n);
    const double k_nn = n.dot(collision_matrix(a, b, impact.point) * n);
    EXPECT_NEAR(k_nn, thesis, 1e-13 * thesis);
  }
}

TEST(ImpulseResponse, EveryImpulseConservesLinearAndAngularMomentumOfFreeBodies) {
  // Angular momentum about a fixed world point o: Σ m (c − o) × v + I ω.
  Random random(14);
  const Vector3d origin(0.3, -0.7, 1.1);
  const auto momenta = [&](const Impact& impact, double& scale) {
    Vector3d linear = Vector3d::Zero(), angular = Vector3d::Zero();
    scale = 0;
    for (const FreeBody* body : {&impact.a, &impact.b}) {
      const Vector3d p = body->mass * body->state.linear_velocity;
      const Vector3d orbital = (body->state.centre_of_mass - origin).cross(p);
      const Vector3d spin = body->inertia * body->state.angular_velocity;
      linear += p;
      angular += orbital + spin;
      scale += p.norm() + orbital.norm() + spin.norm();
    }
    return std::pair{linear, angular};
  };
  for (const double friction : {0.0, 0.3, 2.0}) {
    for (int trial = 0; trial < 300; ++trial) {
      Impact impact = random_impact(random);
      const double restitution = random.uniform(0, 1);
      double scale_before = 0, scale_after = 0;
      const auto [linear_before, angular_before] = momenta(impact, scale_before);
      const CollisionImpulse response =
          collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, restitution, friction);
      apply(impact, response.impulse);
      const auto [linear_after, angular_after] = momenta(impact, scale_after);
      const double scale = std::max(scale_before, scale_after);
      EXPECT_LE((linear_after - linear_before).norm(), 1e-12 * scale) << "friction " << friction;
      EXPECT_LE((angular_after - angular_before).norm(), 1e-12 * scale) << "friction " << friction;
    }
  }
}

TEST(ImpulseResponse, NormalRelativeVelocityReversesScaledByRestitution) {
  // Eq. 2.32, with and without friction, sliding or sticking.
  Random random(15);
  for (const double friction : {0.0, 0.2, 1.0}) {
    for (int trial = 0; trial < 300; ++trial) {
      Impact impact = random_impact(random);
      const double restitution = random.uniform(0, 1);
      const double before = relative_velocity(impact).dot(impact.normal);
      const CollisionImpulse response =
          collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, restitution, friction);
      apply(impact, response.impulse);
      EXPECT_NEAR(relative_velocity(impact).dot(impact.normal), -restitution * before, 1e-12 * (1 + std::abs(before)));
      EXPECT_GT(response.normal_impulse, 0);
      EXPECT_NEAR(response.normal_impulse, response.impulse.dot(impact.normal), 1e-12 * response.impulse.norm());
    }
  }
}

TEST(ImpulseResponse, PlasticImpactLeavesNoNormalRelativeVelocity) {
  Random random(16);
  for (int trial = 0; trial < 200; ++trial) {
    Impact impact = random_impact(random);
    const double before = relative_velocity(impact).dot(impact.normal);
    apply(impact, collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, 0, 0).impulse);
    EXPECT_NEAR(relative_velocity(impact).dot(impact.normal), 0, 1e-12 * std::abs(before));
  }
}

TEST(ImpulseResponse, ElasticFrictionlessImpactConservesKineticEnergy) {
  Random random(17);
  for (int trial = 0; trial < 300; ++trial) {
    Impact impact = random_impact(random);
    const double before = kinetic_energy(impact);
    apply(impact, collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, 1, 0).impulse);
    EXPECT_NEAR(kinetic_energy(impact), before, 1e-12 * before);
  }
}

TEST(ImpulseResponse, FrictionlessImpactNeverGainsKineticEnergy) {
  // ΔE = ½ j_n (1 − e) v_n ≤ 0 for e ≤ 1, exactly.
  Random random(18);
  for (int trial = 0; trial < 500; ++trial) {
    Impact impact = random_impact(random);
    const double before = kinetic_energy(impact);
    const double restitution = random.uniform(0, 1);
    apply(impact, collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, restitution, 0).impulse);
    EXPECT_LE(kinetic_energy(impact), before * (1 + 1e-12));
  }
}

TEST(ImpulseResponse, SeparatingBodiesGetNoImpulse) {
  Random random(19);
  for (int trial = 0; trial < 100; ++trial) {
    Impact impact = random_impact(random);
    impact.normal = -impact.normal;  // now the points move apart along n
    for (const double friction : {0.0, 1.0}) {
      const CollisionImpulse response =
          collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, 0.5, friction);
      EXPECT_EQ(response.impulse, Vector3d::Zero());
      EXPECT_EQ(response.normal_impulse, 0);
      EXPECT_FALSE(response.sliding);
    }
    const Vector3d centres_apart = (impact.a.state.linear_velocity - impact.b.state.linear_velocity).normalized();
    EXPECT_EQ(linear_collision_impulse(impact.a.state, impact.b.state, centres_apart, 0.5), Vector3d::Zero());
  }
}

TEST(ImpulseResponse, TwoImmovableBodiesGetNoImpulse) {
  ImpulseBody wall = ground(), floor = ground();
  wall.linear_velocity = {0, 0, -1};  // a moving kinematic body is still immovable by impulses
  const CollisionImpulse response = collision_impulse(wall, floor, Vector3d::Zero(), Vector3d::UnitZ(), 0.5, 0.5);
  EXPECT_EQ(response.impulse, Vector3d::Zero());
  EXPECT_EQ(linear_collision_impulse(wall, floor, Vector3d::UnitZ(), 0.5), Vector3d::Zero());
}

TEST(ImpulseResponse, RejectsRestitutionOutsideUnitIntervalAndNegativeFriction) {
  const ImpulseBody body{1, Matrix3d::Identity(), Vector3d::Zero(), Vector3d(0, 0, -1), Vector3d::Zero()};
  EXPECT_THROW(collision_impulse(body, ground(), Vector3d::Zero(), Vector3d::UnitZ(), 1.5, 0), std::invalid_argument);
  EXPECT_THROW(collision_impulse(body, ground(), Vector3d::Zero(), Vector3d::UnitZ(), -0.1, 0), std::invalid_argument);
  EXPECT_THROW(collision_impulse(body, ground(), Vector3d::Zero(), Vector3d::UnitZ(), 0.5, -1), std::invalid_argument);
}

TEST(ImpulseResponse, LinearFormulaIsTheFullResponseForCentralImpact) {
  // r_a and r_b parallel to n: rotation cannot absorb any normal impulse (eq. 2.37 → 2.34).
  Random random(20);
  int tested = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Impact impact = random_impact(random);
    impact.a.state.centre_of_mass = impact.point + random.uniform(0.1, 2) * impact.normal;
    impact.b.state.centre_of_mass = impact.point - random.uniform(0.1, 2) * impact.normal;
    const double approach = relative_velocity(impact).dot(impact.normal);
    if (approach >= 0) continue;  // ω × r ⟂ n, so the approach is the centres' own: same sign test
    const double restitution = random.uniform(0, 1);
    const Vector3d full =
        collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, restitution, 0).impulse;
    const Vector3d linear = linear_collision_impulse(impact.a.state, impact.b.state, impact.normal, restitution);
    EXPECT_TRUE(full.isApprox(linear, 1e-12)) << full.transpose() << " vs " << linear.transpose();
    ++tested;
  }
  EXPECT_GT(tested, 50);
}

TEST(ImpulseResponse, LinearFormulaIsTheFullResponseForInfiniteInertia) {
  Random random(21);
  for (int trial = 0; trial < 200; ++trial) {
    Impact impact = random_impact(random);
    impact.a.state.inverse_inertia.setZero();
    impact.b.state.inverse_inertia.setZero();
    impact.a.state.angular_velocity.setZero();  // so the contact moves with the centres
    impact.b.state.angular_velocity.setZero();
    if (relative_velocity(impact).dot(impact.normal) > 0) impact.normal = -impact.normal;
    const double restitution = random.uniform(0, 1);
    const Vector3d full =
        collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, restitution, 0).impulse;
    const Vector3d linear = linear_collision_impulse(impact.a.state, impact.b.state, impact.normal, restitution);
    EXPECT_TRUE(full.isApprox(linear, 1e-12)) << full.transpose() << " vs " << linear.transpose();
  }
}

TEST(ImpulseResponse, PivotedBarBouncesOffAWallThroughItsMomentOfInertia) {
  // A bar of length L pinned at its end (inertia m L²/3 about the pivot) swings into a wall with
  // its tip: ω' = −e ω, the impulse is (1 + e) |ω| L / (L²/I) and the pivot takes the rest.
  const double mass = 2, length = 0.8, restitution = 0.6;
  const double moment = mass * length * length / 3;
  ImpulseBody bar;
  bar.inverse_inertia = Matrix3d::Identity() / moment;
  bar.angular_velocity = {0, 0, -1.5};  // the tip at (L, 0, 0) moves along −y
  const Vector3d tip(length, 0, 0);
  const CollisionImpulse response = collision_impulse(bar, ground(), tip, Vector3d::UnitY(), restitution, 0.4);
  apply_impulse(bar, tip, response.impulse);
  EXPECT_NEAR(bar.angular_velocity.z(), restitution * 1.5, 1e-14);
  EXPECT_NEAR(response.normal_impulse, (1 + restitution) * 1.5 * length * moment / (length * length), 1e-14);
  EXPECT_FALSE(response.sliding);
  EXPECT_EQ(bar.linear_velocity, Vector3d::Zero());
}

TEST(CoulombFriction, HighFrictionStopsSlidingOnTheGround) {
  // Any body landing while sliding, with μ large enough, leaves with zero tangential contact
  // velocity and −e times its normal one.
  Random random(22);
  int tested = 0;
  for (int trial = 0; trial < 200; ++trial) {
    FreeBody body = random.body();
    const Vector3d point = body.state.centre_of_mass + random.vector(0.5);
    body.state.linear_velocity.z() -= 3;  // make sure the contact point approaches the ground
    if (velocity_at(body.state, point).z() >= 0) continue;
    const double restitution = random.uniform(0, 1);
    const CollisionImpulse response = collision_impulse(body.state, ground(), point, Vector3d::UnitZ(), restitution, 1e6);
    const double before = velocity_at(body.state, point).z();
    apply_impulse(body.state, point, response.impulse);
    const Vector3d after = velocity_at(body.state, point);
    EXPECT_FALSE(response.sliding);
    EXPECT_NEAR(after.x(), 0, 1e-12);
    EXPECT_NEAR(after.y(), 0, 1e-12);
    EXPECT_NEAR(after.z(), -restitution * before, 1e-12);
    ++tested;
  }
  EXPECT_GT(tested, 150);
}

TEST(CoulombFriction, LowFrictionSlidesWithTangentialImpulseMuTimesNormalOpposingTheSliding) {
  Random random(23);
  int slid = 0;
  for (int trial = 0; trial < 200; ++trial) {
    FreeBody body = random.body();
    const Vector3d point = body.state.centre_of_mass + random.vector(0.5);
    body.state.linear_velocity.z() -= 3;
    body.state.linear_velocity.x() += 5;  // fast sliding: more than a small μ can stop
    const Vector3d before = velocity_at(body.state, point);
    if (before.z() >= 0) continue;
    const double friction = 0.1;
    const CollisionImpulse response = collision_impulse(body.state, ground(), point, Vector3d::UnitZ(), 0.3, friction);
    ASSERT_TRUE(response.sliding);
    ++slid;
    const Vector3d tangential_impulse(response.impulse.x(), response.impulse.y(), 0);
    const Vector3d sliding(before.x(), before.y(), 0);
    EXPECT_NEAR(tangential_impulse.norm(), friction * response.normal_impulse, 1e-12 * response.normal_impulse);
    EXPECT_TRUE(tangential_impulse.normalized().isApprox(-sliding.normalized(), 1e-12));
  }
  EXPECT_GT(slid, 100);
}

TEST(CoulombFriction, SpheresNeverGainKineticEnergy) {
  // Uniform spheres (I = 2/5 m R² E) meet along the line of centres, so K does not couple normal
  // and tangent and is isotropic in the tangent plane: then the sticking impulse opposes the
  // tangential velocity and the sliding one cannot reverse it, for any μ.
  Random random(24);
  const auto sphere = [&](double radius) {
    FreeBody body;
    body.mass = random.uniform(0.5, 5);
    body.inertia = 0.4 * body.mass * radius * radius * Matrix3d::Identity();
    body.state.inverse_mass = 1 / body.mass;
    body.state.inverse_inertia = body.inertia.inverse();
    body.state.linear_velocity = random.vector(2);
    body.state.angular_velocity = random.vector(5);
    return body;
  };
  int sticking = 0, sliding = 0;
  for (const double friction : {0.05, 0.3, 1.0, 10.0}) {
    for (int trial = 0; trial < 200; ++trial) {
      const double radius_a = random.uniform(0.1, 1), radius_b = random.uniform(0.1, 1);
      Impact impact{sphere(radius_a), sphere(radius_b), Vector3d::Zero(), random.unit()};
      impact.a.state.centre_of_mass = radius_a * impact.normal;
      impact.b.state.centre_of_mass = -radius_b * impact.normal;
      if (relative_velocity(impact).dot(impact.normal) >= 0) continue;
      const double before = kinetic_energy(impact);
      const CollisionImpulse response = collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal,
                                                          random.uniform(0, 1), friction);
      (response.sliding ? sliding : sticking)++;
      apply(impact, response.impulse);
      EXPECT_LE(kinetic_energy(impact), before * (1 + 1e-12)) << "friction " << friction;
    }
  }
  EXPECT_GT(sticking, 50);
  EXPECT_GT(sliding, 50);
}

TEST(CoulombFriction, FrozenSlidingDirectionCanGainEnergyWhenKCouplesNormalAndTangent) {
  // The documented weakness of the algebraic model (see impulses.hpp): with off-centre contacts
  // some random impacts end with more kinetic energy than they began with. This test pins the
  // finding down so that a better model shows up as a failure here, to be turned around.
  Random random(25);
  int gained = 0, trials = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Impact impact = random_impact(random);
    const double before = kinetic_energy(impact);
    apply(impact, collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal,
                                    random.uniform(0, 1), 1.0)
                      .impulse);
    ++trials;
    if (kinetic_energy(impact) > before * (1 + 1e-9)) ++gained;
  }
  EXPECT_GT(gained, trials / 50);
}

TEST(CoulombFriction, SequentialImpulsesNeverGainEnergyAtAnyFriction) {
  // Normal, then friction along the remaining sliding direction: each impulse is along one
  // direction and at most (1 + e) times what stops motion along it, so energy cannot rise — on
  // the same random impacts where the coupled model above gains.
  Random random(25);
  for (int trial = 0; trial < 2000; ++trial) {
    Impact impact = random_impact(random);
    const double before = kinetic_energy(impact);
    const double restitution = random.uniform(0, 1), friction = trial % 2 ? 1.0 : 0.3;
    const CollisionImpulse response =
        sequential_collision_impulse(impact.a.state, impact.b.state, impact.point, impact.normal, restitution, friction);
    const Vector3d tangential = response.impulse - response.normal_impulse * impact.normal;
    EXPECT_LE(tangential.norm(), friction * response.normal_impulse * (1 + 1e-12));
    apply(impact, response.impulse);
    EXPECT_LE(kinetic_energy(impact), before * (1 + 1e-12));
  }
}

TEST(CoulombFriction, SequentialImpulsesStopSlidingOnTheGroundWithEnoughFriction) {
  // A sphere sliding on the ground: K does not couple n and t, so high friction makes the contact
  // point stick and the normal velocity is −e times before.
  ImpulseBody ball;
  ball.inverse_mass = 0.5;
  ball.inverse_inertia = Eigen::Matrix3d::Identity() / (0.4 * 2 * 0.01);
  ball.centre_of_mass = Vector3d(0, 0, 0.1);
  ball.linear_velocity = Vector3d(3, 1, -2);
  const Vector3d point(0, 0, 0), normal = Vector3d::UnitZ();
  const CollisionImpulse response = sequential_collision_impulse(ball, ground(), point, normal, 0.5, 2.0);
  apply_impulse(ball, point, response.impulse);
  const Vector3d after = velocity_at(ball, point);
  EXPECT_NEAR(after.z(), 1.0, 1e-12);
  EXPECT_LT(after.head<2>().norm(), 1e-12);
  EXPECT_FALSE(response.sliding);
}

}  // namespace
}  // namespace limber
