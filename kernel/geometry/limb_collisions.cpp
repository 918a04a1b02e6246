#include "limber/kernel/geometry/limb_collisions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "limber/kernel/geometry/golden_section.hpp"
#include "limber/kernel/geometry/shape_pairs.hpp"
#include "limber/layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

// The segment's deepest point is a contact of its own only this far (axial) inside either end:
// nearer, the end sphere's contact holds the same point.
constexpr double kEndZone = 0.02;
// Golden-section steps for the deepest point of a segment in a box: the bracket shrinks by
// 0.618 per step, so 40 steps leave 4·10⁻⁹ of the segment's length.
constexpr int kDeepestPointSteps = 40;

LimbSegment model_segment(const Body& body) {
  if (!has_half_extents(body.shape)) return {body.head(), body.tail(), body.shape.radius};
  LimbSegment segment{body.position, body.position, bounding_radius(body.shape)};
  segment.orientation = body.orientation() * body.shape.rotation;
  return segment;
}

// A static primitive as a shape: a mesh triangle is the prism it spans down to its thickness
// below (or the flat triangle), its vertices in `storage`, which must outlive the shape.
PlacedShape placed_shape(const StaticPrimitive& primitive, std::array<Vector3d, 6>& storage) {
  switch (primitive.type) {
    case ColliderType::box: return primitive.box;
    case ColliderType::capsule: return primitive.capsule;
    case ColliderType::mesh: break;
  }
  std::size_t count = 0;
  for (const Vector3d& v : primitive.vertices) storage[count++] = v;
  if (primitive.thickness > 0) {
    for (const Vector3d& v : primitive.vertices) storage[count++] = v - primitive.thickness * primitive.face_normal;
  }
  return ConvexHull{Vector3d::Zero(), Eigen::Matrix3d::Identity(), std::span<const Vector3d>(storage.data(), count)};
}

// A manifold's points as contacts of `first` (and `second`, or static geometry).
void add_manifold_contacts(std::uint32_t first, std::uint32_t second, const Manifold& manifold, std::vector<LimbContact>& out) {
  for (int k = 0; k < manifold.count; ++k) {
    const ManifoldPoint& point = manifold.points[k];
    LimbContact contact;
    contact.first = first, contact.second = second;
    contact.normal = manifold.normal;
    contact.point = point.point;
    contact.separation = point.separation;
    contact.feature = point.id;
    // The static surface's point is point − ½·separation·n (C = n·p − offset, radius 0).
    contact.offset = manifold.normal.dot(point.point) - 0.5 * point.separation;
    out.push_back(contact);
  }
}

// The segment's box, grown by its radius and `grow` (m).
Aabb segment_box(const LimbSegment& limb, double grow) {
  const double reach = limb.radius + grow;
  return {limb.head.cwiseMin(limb.tail).array() - reach, limb.head.cwiseMax(limb.tail).array() + reach};
}

// How far the segment may move before the next broadphase search, m.
double search_reach(const LimbSegment& limb) { return std::max(limb.reach, limb.search_reach); }

BoundingSphere segment_sphere(const LimbSegment& limb) {
  return {0.5 * (limb.head + limb.tail), 0.5 * (limb.head - limb.tail).norm() + limb.radius};
}

bool spheres_within(const BoundingSphere& a, const BoundingSphere& b, double margin) {
  const double reach = a.radius + b.radius + margin;
  return (a.centre - b.centre).squaredNorm() <= reach * reach;
}

// A contact of two limbs at a pair of points of their segments (the closest, or one point and
// the other segment's nearest to it); normal from second to first. Touching axes (distance 0)
// take the normal across both (any across a parallel pair), oriented from the second's middle
// towards the first's.
LimbContact limb_pair_contact(std::uint32_t first, std::uint32_t second, const LimbSegment& a, const LimbSegment& b,
                              const SegmentClosestPoints& closest) {
  Vector3d normal;
  if (closest.distance > 0) {
    normal = (closest.on_first - closest.on_second) / closest.distance;
  } else {
    const Vector3d u = a.head - a.tail, v = b.head - b.tail;
    normal = u.cross(v);
    if (normal.squaredNorm() <= 1e-24 * u.squaredNorm() * v.squaredNorm() || normal.isZero(0)) {
      // Parallel (or a point): any direction across the one that is a segment.
      normal = u.squaredNorm() > 0 ? u.unitOrthogonal() : v.squaredNorm() > 0 ? v.unitOrthogonal() : Vector3d::UnitZ();
    }
    normal.normalize();
    // Segments that truly cross have both midpoints in the plane across the normal (the dot is
    // 0): then the first nonzero of z, x, y decides, upwards first.
    double side = normal.dot((a.head + a.tail) - (b.head + b.tail));
    if (std::abs(side) <= 1e-12 * ((a.head - a.tail).norm() + (b.head - b.tail).norm())) {
      side = normal.z() != 0 ? normal.z() : normal.x() != 0 ? normal.x() : normal.y();
    }
    if (side < 0) normal = -normal;
  }
  LimbContact contact;
  contact.first = first, contact.second = second;
  contact.normal = normal;
  contact.separation = closest.distance - a.radius - b.radius;
  contact.axial_first = closest.s, contact.axial_second = closest.t;
  // Midway between the surface points on_first − r₁n and on_second + r₂n.
  contact.point = 0.5 * (closest.on_first - a.radius * normal + closest.on_second + b.radius * normal);
  return contact;
}

LimbContact limb_pair_contact(std::uint32_t first, std::uint32_t second, const LimbSegment& a, const LimbSegment& b) {
  return limb_pair_contact(first, second, a, b, closest_points_between_segments(a.head, a.tail, b.head, b.tail));
}

// Limbs within this angle of parallel lying along each other touch along a line, not at a point.
const double kParallelSine = std::sin(15.0 * std::numbers::pi / 180);

// The point of segment q0–q1 nearest `point`, as a SegmentClosestPoints with `point` first at s.
SegmentClosestPoints nearest_on(const Vector3d& point, double s, const Vector3d& q0, const Vector3d& q1) {
  const Vector3d d = q1 - q0;
  const double length2 = d.squaredNorm();
  const double t = length2 > 0 ? std::clamp((point - q0).dot(d) / length2, 0.0, 1.0) : 0.0;
  SegmentClosestPoints closest;
  closest.on_first = point, closest.on_second = q0 + t * d;
  closest.s = s, closest.t = t;
  closest.distance = (closest.on_first - closest.on_second).norm();
  return closest;
}

// The contacts of two limbs within `reach`: one at the closest points and, for limbs lying along
// each other (within kParallelSine of parallel), one at each end of the length they share, away
// from the first (a contact manifold: one point would let them rock about it, end over end).
// Ends whose normal disagrees with the closest points' (a pair crossed through) are left out.
void add_limb_pair_contacts(std::uint32_t first, std::uint32_t second, const LimbSegment& a, const LimbSegment& b,
                            double reach, std::vector<LimbContact>& out) {
  const LimbContact main = limb_pair_contact(first, second, a, b);
  if (!(main.separation <= reach)) return;
  out.push_back(main);
  const Vector3d u = a.tail - a.head, v = b.tail - b.head;
  const double lengths = u.norm() * v.norm();
  if (!(lengths > 0) || u.cross(v).norm() > kParallelSine * lengths) return;
  // b's ends on a's axis: the shared length is [low, high] of a's parameter.
  const double u2 = u.squaredNorm();
  const double s0 = std::clamp((b.head - a.head).dot(u) / u2, 0.0, 1.0), s1 = std::clamp((b.tail - a.head).dot(u) / u2, 0.0, 1.0);
  const double apart = (a.radius + b.radius) / std::sqrt(u2);  // contacts closer than a diameter hold the same point
  for (const double s : {std::min(s0, s1), std::max(s0, s1)}) {
    if (std::abs(s - main.axial_first) <= apart) continue;
    const LimbContact end = limb_pair_contact(first, second, a, b, nearest_on(a.head + s * u, s, b.head, b.tail));
    if (end.separation <= reach && end.normal.dot(main.normal) > 0) out.push_back(end);
  }
}

// The deepest point of the segment in the shape, as an axial parameter: exact for a capsule and
// a triangle; for a box by golden-section search, as the signed distance to a convex set is
// convex along a line.
double deepest_axial(const StaticPrimitive& primitive, const LimbSegment& limb) {
  switch (primitive.type) {
    case ColliderType::capsule:
      return closest_points_between_segments(limb.head, limb.tail, primitive.capsule.a, primitive.capsule.b).s;
    case ColliderType::mesh:
      return segment_closest_to_triangle(limb.head, limb.tail, primitive.vertices, primitive.face_normal);
    case ColliderType::box: break;
  }
  const auto depth_at = [&](double s) {
    return box_surface_point(primitive.box, limb.head + s * (limb.tail - limb.head)).distance;
  };
  const GoldenBracket deepest = golden_section(depth_at, 0.0, 1.0, kDeepestPointSteps, [](double, double) { return false; });
  return 0.5 * (deepest.low + deepest.high);
}

// One point of the limb against the shape: at axial a, its sphere's separation.
struct Candidate {
  double axial = 0;
  SurfacePoint surface;
  double separation = std::numeric_limits<double>::infinity();  // ∞: the shape ignores the point
};

Candidate candidate_at(const StaticPrimitive& primitive, const LimbSegment& limb, double axial) {
  Candidate candidate;
  candidate.axial = axial;
  const std::optional<SurfacePoint> surface = surface_point(primitive, limb.head + axial * (limb.tail - limb.head));
  if (surface) candidate.surface = *surface, candidate.separation = surface->distance - limb.radius;
  return candidate;
}

// Up to three contacts of the limb and the shape, those within the margin among: its end
// spheres, and the deepest point of its segment when that is inside the limb and deeper than both
// ends (a limb across an edge or a capsule, its ends beyond the shape: a triangle's end sphere
// may find nothing at all). In the order head, tail, middle.
void add_static_contacts(std::uint32_t limb_index, const LimbSegment& limb, const StaticPrimitive& primitive, double margin,
                         std::vector<LimbContact>& out) {
  std::array<Candidate, 3> candidates{candidate_at(primitive, limb, 0), Candidate{}, Candidate{}};
  std::size_t count = 1;
  if (limb.head != limb.tail) {
    candidates[count++] = candidate_at(primitive, limb, 1);
    const double axial = deepest_axial(primitive, limb);
    if (axial >= kEndZone && axial <= 1 - kEndZone) {
      const Candidate middle = candidate_at(primitive, limb, axial);
      if (middle.separation < std::min(candidates[0].separation, candidates[1].separation)) candidates[count++] = middle;
    }
  }
  for (std::size_t k = 0; k < count; ++k) {
    const Candidate& c = candidates[k];
    if (!(c.separation <= margin)) continue;
    LimbContact contact;
    contact.first = limb_index, contact.second = kStaticShape;
    contact.collider = primitive.collider, contact.triangle = primitive.triangle;
    contact.normal = c.surface.normal;
    contact.separation = c.separation;
    contact.axial_first = c.axial;
    // C = n·p(a) − offset = n·(q + d·n) − n·q − r = d − r, the separation.
    contact.offset = c.surface.normal.dot(c.surface.point) + limb.radius;
    contact.point = c.surface.point + 0.5 * c.separation * c.surface.normal;
    contact.friction = primitive.friction, contact.restitution = primitive.restitution;
    out.push_back(contact);
  }
}

// The narrowphase's blocks: candidate pairs (or kept static pairs), and segments whose static
// queries one block runs. About 5 µs of work a block, so a hand-off to a thread pays.
constexpr std::size_t kPairsPerBlock = 64, kSegmentsPerBlock = 32;

bool contact_before(const LimbContact& a, const LimbContact& b) {
  if (a.first != b.first) return a.first < b.first;
  if (a.second != b.second) return a.second < b.second;
  if (a.collider != b.collider) return a.collider < b.collider;
  if (a.triangle != b.triangle) return a.triangle < b.triangle;
  if (a.axial_first != b.axial_first) return a.axial_first < b.axial_first;
  return a.feature < b.feature;
}

}  // namespace

PlacedShape placed_shape(const Shape& shape, const LimbSegment& segment) {
  if (!has_half_extents(shape)) return Capsule{segment.head, segment.tail, segment.radius};
  const Eigen::Matrix3d rotation = segment.orientation.toRotationMatrix();
  if (shape.type == ShapeType::box) return Obb{segment.head, shape.half_extents, rotation};
  return Ellipsoid{segment.head, shape.half_extents, rotation};
}

// Bodies welded by fixed joints are one rigid body (a compound shape: MuJoCo's weld bodies, a
// torso of two capsules), so a joint joins their whole groups: no two of a group collide, nor any
// two across a joint between groups. Without fixed joints, the joined pairs alone.
namespace {

// A body that collides with nothing (a serial joint's virtual link, scene/serial_links.hpp).
bool collides_with_nothing(const Body& body) { return body.collision.group == 0 || body.collision.mask == 0; }

// The pairs of bodies that joints join: directly, or through bodies that collide with nothing (a
// hip's three hinges join the pelvis and the thigh through two virtual links).
std::vector<std::pair<std::uint32_t, std::uint32_t>> joined_pairs(const Model& model) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  const auto body_count = static_cast<std::uint32_t>(model.bodies.size());
  DisjointSets through(body_count);  // the bodies that collide with nothing, joined among themselves
  bool any_ghost = false;
  for (const Joint& joint : model.joints) {
    if (joint.inboard == kWorld || joint.inboard == joint.outboard) continue;
    const auto a = static_cast<std::uint32_t>(joint.inboard), b = static_cast<std::uint32_t>(joint.outboard);
    const bool a_ghost = collides_with_nothing(model.bodies[a]), b_ghost = collides_with_nothing(model.bodies[b]);
    if (!a_ghost && !b_ghost) pairs.emplace_back(a, b);
    if (a_ghost && b_ghost) through.unite(a, b);
    any_ghost |= a_ghost || b_ghost;
  }
  if (!any_ghost) return pairs;
  std::vector<std::vector<std::uint32_t>> ends(body_count);  // per ghost group: the bodies jointed to it
  for (const Joint& joint : model.joints) {
    if (joint.inboard == kWorld) continue;
    const auto a = static_cast<std::uint32_t>(joint.inboard), b = static_cast<std::uint32_t>(joint.outboard);
    if (collides_with_nothing(model.bodies[a]) && !collides_with_nothing(model.bodies[b])) ends[through.find(a)].push_back(b);
    if (collides_with_nothing(model.bodies[b]) && !collides_with_nothing(model.bodies[a])) ends[through.find(b)].push_back(a);
  }
  for (const std::vector<std::uint32_t>& group : ends) {
    for (std::size_t i = 0; i < group.size(); ++i) {
      for (std::size_t k = i + 1; k < group.size(); ++k) pairs.emplace_back(group[i], group[k]);
    }
  }
  return pairs;
}

}  // namespace

void LimbCollisions::exclude_joined_pairs(const Model& model) {
  DisjointSets welded(limb_count_);
  bool any_welded = false;
  for (const Joint& joint : model.joints) {
    if (joint.type != JointType::fixed || joint.inboard == kWorld) continue;
    welded.unite(static_cast<std::uint32_t>(joint.inboard), static_cast<std::uint32_t>(joint.outboard)), any_welded = true;
  }
  std::vector<std::vector<std::uint32_t>> members(any_welded ? limb_count_ : 0);  // per group's representative
  for (std::uint32_t b = 0; b < members.size(); ++b) members[welded.find(b)].push_back(b);
  const auto exclude = [&](std::uint32_t a, std::uint32_t b) {
    if (a != b) excluded_.emplace_back(std::min(a, b), std::max(a, b));
  };
  for (const auto& [a, b] : joined_pairs(model)) {
    if (!any_welded) {
      exclude(a, b);
      continue;
    }
    for (std::uint32_t x : members[welded.find(a)]) {
      for (std::uint32_t y : members[welded.find(b)]) exclude(x, y);
    }
  }
}

LimbCollisions::LimbCollisions(const Model& model)
    : limb_count_(static_cast<std::uint32_t>(model.bodies.size())),
      limb_friction_(model.settings.limb_friction),
      statics_(model.colliders) {
  const std::size_t segments = limb_count_ + model.balls.size();
  std::vector<LimbSegment> limbs;
  limbs.reserve(segments);
  for (const Body& body : model.bodies) {
    limbs.push_back(model_segment(body));
    filters_.push_back(body.collision);
    shapes_.push_back(body.shape);
  }
  restitution_.assign(limb_count_, 0.0);
  for (const Ball& ball : model.balls) {
    limbs.push_back({ball.position, ball.position, ball.radius});
    filters_.emplace_back();  // a ball meets everything its default filter allows
    shapes_.push_back(Shape{ShapeType::capsule, 0, ball.radius});
    restitution_.push_back(ball.restitution);
  }

  // Exclusions: joined pairs, and limb pairs overlapping at the Model's poses (found by the sweep,
  // when any two limbs' filters let them meet: the exclusions answer only for those).
  exclude_joined_pairs(model);
  boxes_.resize(segments);
  std::sort(excluded_.begin(), excluded_.end());
  excluded_.erase(std::unique(excluded_.begin(), excluded_.end()), excluded_.end());
  if (some_pair_tested(/*balls=*/false)) {
    for (std::uint32_t i = 0; i < limb_count_; ++i) boxes_[i] = segment_box(limbs[i], 0);
    for (const CandidatePair& pair : broadphase_.find_pairs(std::span<const Aabb>(boxes_).first(limb_count_))) {
      if (overlapping(pair.first, pair.second, limbs)) excluded_.push_back(pair);
    }
    set_up_comparisons_ += broadphase_.comparisons();
    std::sort(excluded_.begin(), excluded_.end());
    excluded_.erase(std::unique(excluded_.begin(), excluded_.end()), excluded_.end());
  }
  excluded_begin_.assign(segments + 1, 0);
  for (const CandidatePair& pair : excluded_) ++excluded_begin_[pair.first + 1];
  std::partial_sum(excluded_begin_.begin(), excluded_begin_.end(), excluded_begin_.begin());
  limb_pairs_ = some_pair_tested(false) || some_pair_tested(true);
  active_ = limb_pairs_ || !statics_.empty();
  all_awake_.assign(segments, 1);
  // Room for a typical scene's search: four candidate (and kept) pairs per segment (a limb among
  // its neighbours in a pile or a fallen figure), one contact per segment and three per segment
  // against static geometry, four candidates per ball; more grow them once.
  broadphase_.reserve(segments, 0, 4 * segments);
  kept_limb_pairs_.reserve(4 * segments), kept_static_pairs_.reserve(3 * segments), searched_.reserve(segments);
  scratch_.reserve(3 * segments);
  ball_candidates_.reserve(limb_count_, model.balls.size(), 4 * model.balls.size());
}

bool LimbCollisions::some_pair_tested(bool balls) {
  // The limbs' (or the balls') distinct filters, with how many segments have each.
  struct FilterClass {
    std::uint32_t group = 0, mask = 0;
    std::uint64_t count = 0;
  };
  const auto key = [](const FilterClass& c) { return std::make_pair(c.group, c.mask); };
  const std::uint32_t begin = balls ? limb_count_ : 0, end = balls ? static_cast<std::uint32_t>(filters_.size()) : limb_count_;
  std::vector<FilterClass> classes;
  classes.reserve(end - begin);
  for (std::uint32_t s = begin; s < end; ++s) classes.push_back({filters_[s].group, filters_[s].mask, 1});
  std::sort(classes.begin(), classes.end(), [&](const FilterClass& a, const FilterClass& b) { return key(a) < key(b); });
  std::size_t distinct = 0;
  for (std::size_t k = 0; k < classes.size(); ++k) {
    if (distinct > 0 && key(classes[distinct - 1]) == key(classes[k])) {
      ++classes[distinct - 1].count;
    } else {
      classes[distinct++] = classes[k];
    }
  }
  classes.resize(distinct);
  // The exclusions are distinct limb pairs: some pair is tested iff the filters allow more pairs
  // than the exclusions remove. Pairs are counted per pair of distinct filters (few: generators
  // and copies repeat theirs), so this costs that count squared, not the segments'.
  std::uint64_t excluded_allowed = 0;
  if (!balls) {
    for (const CandidatePair& pair : excluded_) excluded_allowed += filters_collide(filters_[pair.first], filters_[pair.second]);
  }
  std::uint64_t allowed = 0;
  for (std::size_t a = 0; a < classes.size(); ++a) {
    for (std::size_t b = a; b < classes.size(); ++b) {
      ++set_up_comparisons_;
      if (!filters_collide({classes[a].group, classes[a].mask}, {classes[b].group, classes[b].mask})) continue;
      allowed += a == b ? classes[a].count * (classes[a].count - 1) / 2 : classes[a].count * classes[b].count;
      if (allowed > excluded_allowed) return true;
    }
  }
  return false;
}

bool LimbCollisions::overlapping(std::uint32_t first, std::uint32_t second, std::span<const LimbSegment> limbs) const {
  if (!has_half_extents(shapes_[first]) && !has_half_extents(shapes_[second])) {
    return limb_pair_contact(first, second, limbs[first], limbs[second]).separation < 0;
  }
  const Manifold manifold = collide(placed_shape(shapes_[first], limbs[first]), placed_shape(shapes_[second], limbs[second]), 0);
  for (int k = 0; k < manifold.count; ++k) {
    if (manifold.points[k].separation < 0) return true;
  }
  return false;
}

bool LimbCollisions::excluded(std::uint32_t first, std::uint32_t second) const {
  // A segment's few exclusions, scanned: a search over all of them missed the cache per pair.
  const auto [low, high] = std::minmax(first, second);
  for (std::uint32_t k = excluded_begin_[low]; k < excluded_begin_[low + 1]; ++k) {
    if (excluded_[k].second == high) return true;
  }
  return false;
}

bool LimbCollisions::pair_tested(std::uint32_t first, std::uint32_t second) const {
  const bool first_ball = first >= limb_count_, second_ball = second >= limb_count_;
  if (first_ball != second_ball) return false;  // ball–limb: the ball's own path
  return filters_collide(filters_[first], filters_[second]) && !excluded(first, second);
}

void LimbCollisions::find(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake, double margin,
                          std::vector<LimbContact>& out, BlockRunner* runner) {
  search(limbs, awake, margin, out, /*keep=*/true, runner);
}

bool LimbCollisions::find_kept_pairs(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake, double margin,
                                     std::vector<LimbContact>& out, BlockRunner* runner) {
  out.clear();
  check_sizes(limbs, awake);
  candidate_pairs_ = 0;
  if (!active_) return true;
  if (searched_.size() != limbs.size()) return false;
  for (std::size_t s = 0; s < limbs.size(); ++s) {
    // A pair the search left out was farther apart than margin + both search reaches (boxes,
    // spheres); the pair's distance has since shrunk by at most the two segments' moves.
    if (!awake[s]) continue;
    const LimbSegment& now = limbs[s];
    const LimbSegment& then = searched_[s];
    const BoundingSphere sphere = segment_sphere(now), searched_sphere = segment_sphere(then);
    const double ends = std::max((now.head - then.head).norm(), (now.tail - then.tail).norm());
    const double spheres = (sphere.centre - searched_sphere.centre).norm() + std::max(0.0, sphere.radius - searched_sphere.radius);
    if (std::max(ends, spheres) + now.reach > search_reach(then)) return false;
  }
  const Narrowphase pass{.collisions = this, .limbs = limbs, .awake = awake, .margin = margin, .search = false, .keep = false,
                         .pairs = kept_limb_pairs_, .static_pairs = kept_static_pairs_,
                         .pair_blocks = block_count(kept_limb_pairs_.size(), kPairsPerBlock),
                         .static_blocks = block_count(kept_static_pairs_.size(), kPairsPerBlock)};
  run_narrowphase(pass, out, /*keep=*/false, runner);
  return true;
}

void LimbCollisions::check_sizes(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake) const {
  const std::size_t segments = filters_.size();
  if (limbs.size() != segments || awake.size() != segments) {
    throw std::invalid_argument("LimbCollisions::find: expected " + std::to_string(segments) + " segments and awake flags, got " +
                                std::to_string(limbs.size()) + " and " + std::to_string(awake.size()));
  }
}

void LimbCollisions::search(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake, double margin,
                            std::vector<LimbContact>& out, bool keep, BlockRunner* runner) {
  out.clear();
  check_sizes(limbs, awake);
  candidate_pairs_ = 0;
  if (keep) kept_limb_pairs_.clear(), kept_static_pairs_.clear(), searched_.assign(limbs.begin(), limbs.end());
  if (!active_) return;
  std::span<const CandidatePair> pairs;
  if (limb_pairs_) {
    for (std::size_t i = 0; i < limbs.size(); ++i) boxes_[i] = segment_box(limbs[i], margin + search_reach(limbs[i]));
    pairs = broadphase_.find_pairs(boxes_);
    candidate_pairs_ = pairs.size();
  }
  const std::size_t segments = statics_.empty() ? 0 : filters_.size();
  const Narrowphase pass{.collisions = this, .limbs = limbs, .awake = awake, .margin = margin, .search = true, .keep = keep,
                         .pairs = pairs, .static_pairs = {},
                         .pair_blocks = block_count(pairs.size(), kPairsPerBlock),
                         .static_blocks = block_count(segments, kSegmentsPerBlock)};
  run_narrowphase(pass, out, keep, runner);
}

void LimbCollisions::run_block(const Narrowphase& pass, std::size_t index, std::vector<LimbContact>& contacts,
                               std::vector<CandidatePair>& kept) const {
  const bool pairs = index < pass.pair_blocks;
  const std::size_t per_block = pairs || !pass.search ? kPairsPerBlock : kSegmentsPerBlock;
  const std::size_t total = pairs ? pass.pairs.size() : pass.search ? filters_.size() : pass.static_pairs.size();
  const std::size_t begin = (pairs ? index : index - pass.pair_blocks) * per_block, end = std::min(total, begin + per_block);
  if (pairs && pass.search) {
    search_limb_pairs(pass.pairs.subspan(begin, end - begin), pass.limbs, pass.awake, pass.margin, pass.keep, contacts, kept);
  } else if (pairs) {
    for (const auto& [i, j] : pass.pairs.subspan(begin, end - begin)) {
      if (pass.awake[i] || pass.awake[j]) add_limb_pair(i, j, pass.limbs, pass.margin, contacts);
    }
  } else if (pass.search) {
    search_static(static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end), pass.limbs, pass.awake, pass.margin, pass.keep,
                  contacts, kept);
  } else {
    for (const auto& [s, k] : pass.static_pairs.subspan(begin, end - begin)) {
      if (pass.awake[s]) add_static_pair(s, pass.limbs[s], statics_.primitives()[k], pass.margin, contacts);
    }
  }
}

double LimbCollisions::Narrowphase::run(const void* context, std::size_t index) {
  const Narrowphase& pass = *static_cast<const Narrowphase*>(context);
  Block& block = pass.blocks[index];
  block.contacts.clear(), block.kept.clear();
  pass.collisions->run_block(pass, index, block.contacts, block.kept);
  return 0;
}

void LimbCollisions::run_narrowphase(const Narrowphase& pass, std::vector<LimbContact>& out, bool keep, BlockRunner* runner) {
  const std::size_t count = pass.pair_blocks + pass.static_blocks;
  if (runner == nullptr || runner->threads() == 1 || count <= 1) {
    // One thread: each block straight into the lists, in block order (what the join below gives).
    for (std::size_t index = 0; index < count; ++index) {
      run_block(pass, index, out, index < pass.pair_blocks ? kept_limb_pairs_ : kept_static_pairs_);
    }
    std::sort(out.begin(), out.end(), contact_before);
    return;
  }
  while (blocks_.size() < count) {
    // A limb-pair block gives at most two contacts a pair; a static block's typical three a segment.
    Block& block = blocks_.emplace_back();
    block.contacts.reserve(2 * kPairsPerBlock), block.kept.reserve(std::max(kPairsPerBlock, 3 * kSegmentsPerBlock));
  }
  Narrowphase stage = pass;
  stage.blocks = blocks_.data();
  run_stage(runner, count, &Narrowphase::run, &stage);
  for (std::size_t index = 0; index < count; ++index) {
    const Block& block = blocks_[index];
    out.insert(out.end(), block.contacts.begin(), block.contacts.end());
    if (!keep) continue;
    std::vector<CandidatePair>& kept = index < pass.pair_blocks ? kept_limb_pairs_ : kept_static_pairs_;
    kept.insert(kept.end(), block.kept.begin(), block.kept.end());
  }
  std::sort(out.begin(), out.end(), contact_before);
}

void LimbCollisions::add_limb_pair(std::uint32_t i, std::uint32_t j, std::span<const LimbSegment> limbs, double margin,
                                   std::vector<LimbContact>& out) const {
  const double reach = margin + limbs[i].reach + limbs[j].reach;
  if (!spheres_within(segment_sphere(limbs[i]), segment_sphere(limbs[j]), reach)) return;
  const std::size_t begin = out.size();
  if (has_half_extents(shapes_[i]) || has_half_extents(shapes_[j])) {
    add_manifold_contacts(i, j, collide(placed_shape(shapes_[i], limbs[i]), placed_shape(shapes_[j], limbs[j]), reach), out);
  } else {
    add_limb_pair_contacts(i, j, limbs[i], limbs[j], reach, out);
  }
  // Limbs have no restitution and rub with the limbs' friction; balls have no friction.
  const double friction = i < limb_count_ ? limb_friction_ : 0.0;
  const double restitution = std::max(restitution_[i], restitution_[j]);
  for (std::size_t k = begin; k < out.size(); ++k) out[k].friction = friction, out[k].restitution = restitution;
}

void LimbCollisions::add_static_pair(std::uint32_t s, const LimbSegment& limb, const StaticPrimitive& primitive, double margin,
                                     std::vector<LimbContact>& out) const {
  const double reach = margin + limb.reach;
  if (!spheres_within(segment_sphere(limb), primitive.sphere, reach)) return;
  const std::size_t begin = out.size();
  if (has_half_extents(shapes_[s])) {
    std::array<Vector3d, 6> vertices;
    add_manifold_contacts(s, kStaticShape, collide(placed_shape(shapes_[s], limb), placed_shape(primitive, vertices), reach), out);
    for (std::size_t k = begin; k < out.size(); ++k) {
      out[k].collider = primitive.collider, out[k].triangle = primitive.triangle;
      out[k].friction = primitive.friction, out[k].restitution = primitive.restitution;
    }
  } else {
    add_static_contacts(s, limb, primitive, reach, out);
  }
  // A ball bounces with the larger of its restitution and the collider's, as on the ground.
  for (std::size_t k = begin; k < out.size(); ++k) out[k].restitution = std::max(out[k].restitution, restitution_[s]);
}

void LimbCollisions::search_limb_pairs(std::span<const CandidatePair> pairs, std::span<const LimbSegment> limbs,
                                       std::span<const std::uint8_t> awake, double margin, bool keep, std::vector<LimbContact>& contacts,
                                       std::vector<CandidatePair>& kept) const {
  for (const auto& [i, j] : pairs) {
    if (!awake[i] && !awake[j]) continue;
    if (!pair_tested(i, j)) continue;
    if (!spheres_within(segment_sphere(limbs[i]), segment_sphere(limbs[j]), margin + search_reach(limbs[i]) + search_reach(limbs[j]))) continue;
    if (keep) kept.emplace_back(i, j);
    add_limb_pair(i, j, limbs, margin, contacts);
  }
}

void LimbCollisions::search_static(std::uint32_t begin, std::uint32_t end, std::span<const LimbSegment> limbs,
                                   std::span<const std::uint8_t> awake, double margin, bool keep, std::vector<LimbContact>& contacts,
                                   std::vector<CandidatePair>& kept) const {
  const StaticPrimitive* first = statics_.primitives().data();
  for (std::uint32_t s = begin; s < end; ++s) {
    if (!awake[s]) continue;
    const LimbSegment& limb = limbs[s];
    const BoundingSphere sphere = segment_sphere(limb);
    const double reach = margin + search_reach(limb);
    statics_.query(segment_box(limb, reach), [&](const StaticPrimitive& primitive) {
      if (!filters_collide(filters_[s], primitive.filter)) return;
      if (!spheres_within(sphere, primitive.sphere, reach)) return;
      if (keep) kept.emplace_back(s, static_cast<std::uint32_t>(&primitive - first));
      add_static_pair(s, limb, primitive, margin, contacts);
    });
  }
}

SweptTouch LimbCollisions::first_static_touch(std::uint32_t segment, const Vector3d& from, const Vector3d& to, double radius) const {
  SweptTouch first;
  const Vector3d path = to - from;
  const Aabb box{from.cwiseMin(to).array() - radius, from.cwiseMax(to).array() + radius};
  statics_.query(box, [&](const StaticPrimitive& primitive) {
    if (!filters_collide(filters_[segment], primitive.filter)) return;
    const std::optional<SurfacePoint> start = surface_point(primitive, from);
    if (start && start->distance - radius < -kSweptSlop * radius) return;
    const TimeOfImpact impact = sphere_static_time_of_impact(from, to, radius, primitive);
    if (!impact.hit || !(impact.time < first.time)) return;
    const std::optional<SurfacePoint> touch = surface_point(primitive, from + impact.time * path);
    const std::optional<SurfacePoint> end = surface_point(primitive, to);
    if (!touch) return;
    const double end_separation = end ? end->distance - radius : std::numeric_limits<double>::infinity();
    if (answer_at_touch(path, impact.time, touch->normal, radius, end_separation, end ? end->normal : touch->normal)) {
      first.keep_if_earlier(impact.time, touch->normal, touch->distance - radius);
    }
  });
  return first;
}

LimbContact LimbCollisions::deepest_overlap(std::span<const LimbSegment> limbs) {
  search(limbs, all_awake_, 0, scratch_, /*keep=*/false, /*runner=*/nullptr);
  LimbContact deepest;
  for (const LimbContact& contact : scratch_) {
    if (contact.separation < deepest.separation) deepest = contact;  // the first of equals: the contacts' fixed order
  }
  return deepest;
}

}  // namespace limber
