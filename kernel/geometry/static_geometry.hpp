// Static level geometry (Model::colliders) for the limb collision world (limb_collisions.hpp):
// the closest surface point of a box, a capsule or a one-sided triangle to a point, and a
// bounding volume tree over every collider and mesh triangle, built once.
//
// A point query answers the static side of a limb–static contact: the surface point q, the unit
// normal n out of the surface towards the point p and the signed distance d (< 0 inside), with
// p = q + d·n. A limb end sphere of radius r then has separation d − r.
//
// The tree (Ericson, "Real-Time Collision Detection", 6.1–6.2): each node's box holds its
// primitives; a node splits at the median of its primitives' centres along the axis where they
// spread most (a balanced tree, depth ≤ log₂ n + 1), down to leaves of at most
// kLeafPrimitives. Queries walk it with a fixed stack: no allocation.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// The static surface point nearest a query point p: p = point + distance·normal.
struct SurfacePoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    ///< m, on the surface
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, out of the surface towards p
  double distance = 0;                                ///< m, signed: < 0 inside
};

/// A box: outside, from its closest point; inside, out through the nearest face (distance < 0).
SurfacePoint box_surface_point(const Obb& box, const Eigen::Vector3d& p);

/// A capsule: from its core segment's closest point, out through its radius. A point on the core
/// leaves perpendicular to it (or along +z for a sphere).
SurfacePoint capsule_surface_point(const Capsule& capsule, const Eigen::Vector3d& p);

/// The point of triangle a, b, c nearest p (Ericson 5.1.5, by Voronoi regions).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                          const Eigen::Vector3d& p);

/// A one-sided triangle a, b, c (counter-clockwise from outside, `face_normal` its unit normal):
/// a point behind its plane by at most `thickness` whose projection falls inside it leaves
/// through the face (distance: the signed plane distance, ≤ 0); a point farther behind, or behind
/// beside it, is not its business (nullopt: a neighbouring face or nothing answers); a point in
/// front takes the closest point of the triangle.
std::optional<SurfacePoint> triangle_surface_point(const std::array<Eigen::Vector3d, 3>& triangle,
                                                   const Eigen::Vector3d& face_normal, double thickness,
                                                   const Eigen::Vector3d& p);

/// The parameter s ∈ [0, 1] of the point p0 + s(p1 − p0) nearest the triangle (exact: the
/// segment's crossing of the triangle, its ends against the triangle, or its closest points to
/// the edges).
double segment_closest_to_triangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                   const std::array<Eigen::Vector3d, 3>& triangle, const Eigen::Vector3d& face_normal);

/// One static shape in the tree: a box, a capsule, or one triangle of a mesh, with what a contact
/// needs of its collider.
struct StaticPrimitive {
  ColliderType type = ColliderType::box;
  std::uint32_t collider = 0;                        ///< Model::colliders index
  std::uint32_t triangle = 0;                        ///< mesh: the triangle's index; else 0
  Obb box;                                           ///< box
  Capsule capsule;                                   ///< capsule
  std::array<Eigen::Vector3d, 3> vertices{};         ///< mesh triangle, m
  Eigen::Vector3d face_normal = Eigen::Vector3d::UnitZ();  ///< mesh triangle, unit
  double thickness = 0;                              ///< mesh, m
  double friction = 0, restitution = 0;
  CollisionFilter filter;
  Aabb bounds;                                       ///< m, tight
  BoundingSphere sphere;                             ///< m, about the bounds' centre
};

/// The nearest surface point of `primitive` to p, as the functions above (nullopt: a triangle
/// that ignores p).
std::optional<SurfacePoint> surface_point(const StaticPrimitive& primitive, const Eigen::Vector3d& p);

/// Every collider's primitives in a median-split bounding volume tree, built once.
class StaticTree {
 public:
  StaticTree() = default;
  explicit StaticTree(const std::vector<StaticCollider>& colliders);

  bool empty() const { return primitives_.empty(); }
  const std::vector<StaticPrimitive>& primitives() const { return primitives_; }

  /// Calls visit(primitive) for each primitive whose bounds overlap `box` (touching counts), in
  /// the tree's fixed order. No allocation.
  template <typename Visit>
  void query(const Aabb& box, Visit&& visit) const {
    if (nodes_.empty()) return;
    std::array<std::uint32_t, kMaxDepth> stack;
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!overlaps(node.bounds, box)) continue;
      if (node.count > 0) {
        for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
          if (overlaps(primitives_[k].bounds, box)) visit(primitives_[k]);
        }
      } else {
        stack[top++] = node.first + 1;  // the right child, visited after the left
        stack[top++] = node.first;
      }
    }
  }

 private:
  static constexpr std::uint32_t kLeafPrimitives = 4;
  // A median split halves the count, so 2³² primitives need depth 32; one stack slot per level
  // plus one pending sibling per level fits in 64.
  static constexpr std::size_t kMaxDepth = 64;
  // Inner node: its children at first and first + 1, count 0. Leaf: primitives [first, first + count).
  struct Node {
    Aabb bounds;
    std::uint32_t first = 0;
    std::uint32_t count = 0;
  };
  void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end);

  std::vector<StaticPrimitive> primitives_;
  std::vector<Node> nodes_;
};

}  // namespace limber
