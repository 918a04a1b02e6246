#include "limber/kernel/study/spring_stability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "limber/kernel/springs/compile.hpp"

namespace limber::study {

// The chain's spring-mode frequencies ω (rad/s), from K φ = ω² M φ at the initial pose; rigid
// motions (ω ≈ 0) left out.
std::vector<double> spring_mode_frequencies(const Model& model, double stiffness) {
  const SpringState state = compile_springs(model, {.stiffness = stiffness});
  const RigidBodyBuffer& bodies = state.bodies;
  const RigidBodyState& y = bodies.state;
  const Eigen::Index size = static_cast<Eigen::Index>(6 * bodies.size());
  Eigen::MatrixXd mass = Eigen::MatrixXd::Zero(size, size), spring_stiffness = Eigen::MatrixXd::Zero(size, size);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Eigen::Index at = static_cast<Eigen::Index>(6 * b);
    mass.block<3, 3>(at, at) = bodies.mass[b] * Eigen::Matrix3d::Identity();
    mass.block<3, 3>(at + 3, at + 3) = bodies.world_inertia(y, b);
  }
  const auto skew = [](const Eigen::Vector3d& r) {
    Eigen::Matrix3d m;
    m << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
    return m;
  };
  for (std::size_t j = 0; j < state.springs.size(); ++j) {
    Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(3, size);
    const auto add = [&](std::int32_t body, const Eigen::Vector3d& anchor, double sign) {
      if (body < 0) return;  // the world
      const Eigen::Index at = 6 * body;
      const Eigen::Vector3d r = y.orientation[body] * anchor;
      jacobian.block<3, 3>(0, at) += sign * Eigen::Matrix3d::Identity();
      jacobian.block<3, 3>(0, at + 3) -= sign * skew(r);
    };
    add(state.springs.inboard[j], state.springs.inboard_anchor[j], 1);
    add(state.springs.outboard[j], state.springs.outboard_anchor[j], -1);
    spring_stiffness += stiffness * jacobian.transpose() * jacobian;
  }
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> modes(spring_stiffness, mass, Eigen::EigenvaluesOnly);
  const Eigen::VectorXd squared = modes.eigenvalues();
  std::vector<double> frequencies;
  for (Eigen::Index i = 0; i < squared.size(); ++i) {
    if (squared[i] > 1e-9 * squared.maxCoeff()) frequencies.push_back(std::sqrt(squared[i]));
  }
  return frequencies;
}

// The largest stable step (s) of `integrator` on the chain whose spring modes are `frequencies`,
// springs k (N/m) and c (N·s/m), by the bounds above. Infinity for the implicit step.
double predicted_largest_stable_step(Integrator integrator, const std::vector<double>& frequencies, double stiffness,
                                     double damping) {
  const double ratio = damping / stiffness;  // c/k, s
  double largest = std::numeric_limits<double>::infinity();
  for (const double omega : frequencies) {
    const double gamma = ratio * omega * omega;  // the mode's damping rate, 1/s
    double bound = largest;
    if (integrator == Integrator::semi_implicit_euler) {
      bound = std::sqrt(ratio * ratio + 4 / (omega * omega)) - ratio;
    } else if (integrator == Integrator::euler) {
      bound = gamma < 2 * omega ? ratio : 4 / (gamma + std::sqrt(gamma * gamma - 4 * omega * omega));
    }
    largest = std::min(largest, bound);
  }
  return largest;
}

}  // namespace limber::study
