// The shape-pair table: which narrow-phase function answers each pair of convex shapes.
//
// Every rigid method's contacts between limbs, and between limbs and static colliders, come
// through here (kernel/geometry/limb_collisions.hpp calls it for every pair with a box or an
// ellipsoid), as Box2D v3's `s_registers` and MuJoCo's `mjCOLLISIONFUNC` do: closed forms where
// limber has them (manifolds.hpp: box–box by separating axes, capsule–box, box–plane), libccd's
// GJK/EPA for the rest (convex_pairs.hpp: ellipsoids, cylinders as themselves, hulls).
//
//            capsule            box                 ellipsoid, cylinder, hull
//  capsule   collision world's  capsule_box         convex_manifold
//  box       capsule_box, swap  box_box             convex_manifold
//  others    convex_manifold    convex_manifold     convex_manifold
//
// Two capsules are the collision world's own pair (`add_limb_pair_contacts`,
// limb_collisions.cpp): it also gives the axial parameters the particle method's contact rows
// need, which a manifold does not carry. A swapped pair is the same manifold with the normal
// turned (its points are midway between the surfaces, so they do not move).
//
// How to add a shape: its struct and `support()` in convex_pairs.hpp (and its explicit
// instantiations there), an alternative of PlacedShape, and — only if a closed form pays — an
// overload of `pair_manifold` in shape_pairs.cpp; kernel/PIPELINE.md has the whole recipe.
#pragma once

#include <variant>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/geometry/convex_pairs.hpp"
#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/geometry/manifolds.hpp"

namespace limber {

/// A convex shape placed in the world, as the narrow phase sees it. A sphere is a capsule whose
/// ends coincide.
using PlacedShape = std::variant<Capsule, Obb, Ellipsoid, Cylinder, ConvexHull>;

/// `first` against `second` within `margin` (m, ≥ 0): up to four points, normal from the second
/// towards the first (manifolds.hpp's conventions). Throws std::invalid_argument for two capsules
/// (the collision world's pair, above).
Manifold collide(const PlacedShape& first, const PlacedShape& second, double margin);

/// `shape` against the half-space n·x ≥ plane.offset (the shape first, normal = n) within
/// `margin`: a box's deepest vertices (box_plane_manifold), any other shape's deepest point
/// (its support along −n), with id 0.
Manifold collide(const PlacedShape& shape, const Plane& plane, double margin);

/// The manifold with first and second swapped: the normal turned, the points and ids kept.
inline Manifold swapped(Manifold manifold) {
  manifold.normal = -manifold.normal;
  return manifold;
}

}  // namespace limber
