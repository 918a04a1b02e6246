// One contact's step of projected Gauss–Seidel: its accumulated impulse moved to answer the
// contact's own rows, then projected back into Coulomb's cone.
//
// A contact has a unit normal n, a 3×3 collision matrix K (symmetric positive semi-definite:
// the change of its points' relative velocity u per unit impulse, K = J H⁻¹ Jᵀ of its three
// rows; Mirtich 1996) and an accumulated impulse λ (N·s), both in the contact's frame (normal,
// t₁, t₂). A step of the contact, with the other contacts' impulses held (Gauss–Seidel):
//   the normal  λ_n' = max(λ_n + (t − n·u)/(nᵀKn), 0): the normal speed reaches its target t
//               (m/s: a bounce, or a gap the step may close) and the contact never pulls;
//   friction    λ_t' = argmin over |λ_t'| ≤ μ·λ_n' of the tangential rows' energy: the tangential
//               speed stopped through K's 2×2 tangent block at the new normal impulse when that
//               stays in Coulomb's disc, else the disc's edge where the friction opposes the slip
//               it leaves (maximal dissipation; MuJoCo's PGS on an elliptic cone, mju_QCQP2 —
//               clamping the stopping impulse to the disc, Box2D's way, converges to a slip
//               along −K_tt λ_t instead).
// Each step lowers ½λᵀAλ + λᵀ(u₀ − t) over its own contact (A the Delassus matrix of all the
// contacts, u₀ their speeds before any impulse), so the passes converge to the complementarity
// problem's answer (Cottle, Pang & Stone 1992, §5.2), the more slowly the more the contacts are
// coupled; started from the last step's impulses (warm start), a resting scene begins at its
// answer.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// A contact's frame: its unit normal n and two unit tangents t₁ = n.unitOrthogonal(), t₂ = n × t₁
/// (rows of the matrix: world → contact frame).
inline Eigen::Matrix3d contact_frame(const Eigen::Vector3d& normal) {
  Eigen::Matrix3d frame;
  const Eigen::Vector3d t1 = normal.unitOrthogonal();
  frame.row(0) = normal.transpose(), frame.row(1) = t1.transpose(), frame.row(2) = normal.cross(t1).transpose();
  return frame;
}

/// The λ minimizing ½λᵀAλ + gᵀλ over the disc |λ| ≤ radius, A (a, b; b, c) symmetric positive
/// semi-definite: inside it A⁻¹ solves it; on its edge (A + μI)λ = −g with μ ≥ 0 the multiplier
/// of |λ| = radius, found by Newton's method on 1/|λ(μ)| = 1/radius — nearly linear in μ, so
/// Newton from the left closes on it in a few steps even where A is singular (Moré & Sorensen
/// 1983, "Computing a trust region step"; MuJoCo's mju_QCQP2 solves the same problem). So the
/// friction opposes the slip it leaves, Aλ + g = −μλ (maximal dissipation), where clamping A⁻¹'s
/// answer to the disc would leave the slip along −Aλ.
inline Eigen::Vector2d disc_minimum(double a, double b, double c, const Eigen::Vector2d& g, double radius) {
  if (!(radius > 0)) return Eigen::Vector2d::Zero();
  const auto solve = [&](double mu, const Eigen::Vector2d& x) {  // (A + μI)⁻¹x
    const double p = a + mu, r = c + mu, determinant = p * r - b * b;
    return Eigen::Vector2d((r * x.x() - b * x.y()) / determinant, (p * x.y() - b * x.x()) / determinant);
  };
  double mu = 0;
  if (a * c - b * b > 1e-12 * a * c && a > 0) {
    const Eigen::Vector2d inside = -solve(0, g);
    if (inside.squaredNorm() <= radius * radius) return inside;
  } else {
    mu = 1e-12 * std::max(a + c, 1e-300);  // A singular: the edge, at a multiplier that keeps A + μI invertible
  }
  Eigen::Vector2d lambda = -solve(mu, g);
  for (int iteration = 0; iteration < 20; ++iteration) {
    const double size = lambda.norm();
    if (!(size > radius * (1 + 1e-12))) break;
    // ψ(μ) = 1/|λ| − 1/radius, ψ'(μ) = λᵀ(A + μI)⁻¹λ / |λ|³.
    mu += (size / radius - 1) * size * size / lambda.dot(solve(mu, lambda));
    lambda = -solve(mu, g);
  }
  return lambda * (radius / std::max(lambda.norm(), 1e-300));
}

/// The impulse λ' (N·s) after one step of projected Gauss–Seidel on a contact (above), all in the
/// contact's frame (normal, t₁, t₂): `k` its collision matrix (m/s per N·s), `speed` its points'
/// relative velocity u with the impulses so far (m/s), `impulse` its accumulated λ (λ_n ≥ 0,
/// |λ_t| ≤ μλ_n), `target` the normal speed wanted (m/s), `friction` μ ≥ 0. The caller applies
/// λ' − λ. A contact that moves nothing along its normal (k₀₀ ≤ 0) keeps λ.
inline Eigen::Vector3d project_contact_impulse(const Eigen::Matrix3d& k, const Eigen::Vector3d& speed, const Eigen::Vector3d& impulse,
                                               double target, double friction) {
  if (!(k(0, 0) > 0)) return impulse;
  const double normal = std::max(impulse[0] + (target - speed[0]) / k(0, 0), 0.0);
  if (!(friction > 0)) return {normal, 0.0, 0.0};
  // The slip after the normal's change; the friction minimizes ½λ_tᵀK_tt λ_t + λ_tᵀ(slip − K_tt λ_t,old),
  // the tangential rows' energy, within Coulomb's disc at the new normal impulse.
  const double change = normal - impulse[0];
  const Eigen::Vector2d old = impulse.tail<2>();
  const Eigen::Vector2d slip(speed[1] + k(1, 0) * change, speed[2] + k(2, 0) * change);
  const Eigen::Matrix2d tangent = k.bottomRightCorner<2, 2>();
  const Eigen::Vector2d tangential = disc_minimum(tangent(0, 0), 0.5 * (tangent(0, 1) + tangent(1, 0)), tangent(1, 1), slip - tangent * old, friction * normal);
  return {normal, tangential.x(), tangential.y()};
}

}  // namespace limber
