#include "limber/kernel/geometry/separating_axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// Ericson's ε (4.4.1), added to every |R_ij| of the test: far above the rounding of R (~1e-16),
// far below any size that matters (it grows the boxes by ~1e-12 of their size).
constexpr double kParallelEpsilon = 1e-12;
// An edge–edge axis a_i × b_j shorter than this (sine of the angle between the edges) has no
// reliable direction, so it is not used as a contact normal.
constexpr double kMinimumEdgeAxisLength = 1e-6;
// Face normals of the two boxes within 1° of parallel tie (separating_axis_test, below).
const double kParallelFacesCosine = std::cos(std::numbers::pi / 180);

// The best axis of one kind so far: its depth, unit axis (first box's frame) and t·L on it.
struct AxisCandidate {
  double depth = std::numeric_limits<double>::infinity();
  Vector3d axis = Vector3d::UnitZ();
  double offset = 0;
  BoxAxis which;
};

void consider(AxisCandidate& best, double depth, const Vector3d& axis, double offset, BoxAxis which) {
  if (depth < best.depth) best = {depth, axis, offset, which};
}

}  // namespace

// In the first box's frame. R_ij = a_i·b_j expresses the second box's axes in the first's; t is
// the offset of centres there. On an axis L the boxes' projections have radii
// r_A = Σ_k h^A_k |a_k·L| and r_B = Σ_k h^B_k |b_k·L|, and the axis separates when
// |t·L| > r_A + r_B (+ margin·|L|). For L = a_i × b_j the dot products reduce to entries of R
// (with (i, i1, i2) and (j, j1, j2) cyclic):
//   |t·L| = |t_i2 R_i1j − t_i1 R_i2j|,  r_A = h^A_i1 |R_i2j| + h^A_i2 |R_i1j|,
//   r_B = h^B_j1 |R_ij2| + h^B_j2 |R_ij1|,  |L| = √(R_i1j² + R_i2j²).
SeparatingAxisResult separating_axis_test(const Obb& first, const Obb& second, bool find_contact, double margin) {
  const Vector3d& ha = first.half_extents;
  const Vector3d& hb = second.half_extents;
  const Matrix3d r = first.rotation.transpose() * second.rotation;
  const Matrix3d abs_r = r.cwiseAbs();
  // The test uses |R| + ε (so near-parallel edges never separate); depths use |R| itself.
  const Matrix3d abs_r_test = abs_r.array() + kParallelEpsilon;
  const Vector3d t = first.rotation.transpose() * (second.centre - first.centre);

  SeparatingAxisResult result;
  AxisCandidate first_face, second_face, edge;
  // The first box's face normals a_k.
  for (int k = 0; k < 3; ++k) {
    const double distance = std::abs(t[k]);
    if (distance > ha[k] + hb.dot(abs_r_test.row(k)) + margin) return result;
    consider(first_face, ha[k] + hb.dot(abs_r.row(k)) - distance, Vector3d::Unit(k), t[k], {BoxAxis::Kind::first_face, k, 0});
  }
  // The second box's face normals b_k = column k of R.
  for (int k = 0; k < 3; ++k) {
    const double offset = t.dot(r.col(k));
    const double distance = std::abs(offset);
    if (distance > ha.dot(abs_r_test.col(k)) + hb[k] + margin) return result;
    consider(second_face, ha.dot(abs_r.col(k)) + hb[k] - distance, r.col(k), offset, {BoxAxis::Kind::second_face, 0, k});
  }
  // The nine edge–edge axes a_i × b_j.
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double offset = t[i2] * r(i1, j) - t[i1] * r(i2, j);
      const double distance = std::abs(offset);
      const double radius_a_test = ha[i1] * abs_r_test(i2, j) + ha[i2] * abs_r_test(i1, j);
      const double radius_b_test = hb[j1] * abs_r_test(i, j2) + hb[j2] * abs_r_test(i, j1);
      const double length = margin > 0 || find_contact ? std::hypot(r(i1, j), r(i2, j)) : 0.0;
      if (distance > radius_a_test + radius_b_test + margin * length) return result;
      if (!find_contact || length < kMinimumEdgeAxisLength) continue;
      const double radius_a = ha[i1] * abs_r(i2, j) + ha[i2] * abs_r(i1, j);
      const double radius_b = hb[j1] * abs_r(i, j2) + hb[j2] * abs_r(i, j1);
      consider(edge, (radius_a + radius_b - distance) / length, Vector3d::Unit(i).cross(Vector3d(r.col(j))) / length,
               offset / length, {BoxAxis::Kind::edges, i, j});
    }
  }
  result.overlap = true;
  if (!find_contact) return result;

  // Two faces nearly parallel (a box resting on a box) have nearly the same depth, and rounding
  // or a slight rock would swap them step to step, and the manifold's ids with them: the first
  // box's face wins such a tie.
  const bool faces_parallel = std::abs(first_face.axis.dot(second_face.axis)) >= kParallelFacesCosine;
  const AxisCandidate& face = second_face.depth < first_face.depth && !faces_parallel ? second_face : first_face;
  // Overlapping, the edge must be 5 % shallower than either face; apart, its gap 5 % wider. (Against
  // the tie's winner alone, an edge axis near the other face's normal would win the tie back.)
  const double face_depth = std::min(first_face.depth, second_face.depth);
  const double preferred = face_depth >= 0 ? kEdgeAxisPreference * face_depth : (2 - kEdgeAxisPreference) * face_depth;
  const AxisCandidate& best = edge.depth < preferred ? edge : face;
  // t points from the first box to the second: the normal points against it.
  const Vector3d local_normal = best.offset > 0 ? Vector3d(-best.axis) : best.axis;
  result.normal = (first.rotation * local_normal).normalized();
  result.depth = best.depth;
  result.axis = best.which;
  return result;
}

}  // namespace limber
