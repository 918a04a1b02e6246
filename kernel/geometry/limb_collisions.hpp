// The collision world every method shares: limbs against limbs and against static level
// geometry (Model::colliders), found each step from the limbs' segments.
//
// Detection is in three levels, what thesis 2.4 calls the hierarchical test:
// - broadphase: sweep and prune over the limbs' boxes (kernel/geometry/broadphase.hpp), which
//   keeps last step's order (nearly sorted, so incremental); static geometry sits in a bounding
//   volume tree built once, queried with each limb's box;
// - bounding spheres: a pair whose spheres are apart is dropped with one distance;
// - the exact closest points of the limb's capsule (its segment and radius) and the other shape.
// Limbs are capsules here, a cylinder by the capsule around it (its caps stick out r past its
// flat ends; the ground and the bounds still see a cylinder's exact rim, geometry.hpp). A box or
// an ellipsoid limb is its bounding sphere to the broadphase (head = tail = its centre, radius
// bounding_radius) and itself to the narrowphase: every pair with one goes through the shape-pair
// table (shape_pairs.hpp) as a manifold of up to four points.
// Pairs a filter rejects, joined by a joint or overlapping in the Model's poses never reach the
// broadphase's answer (CollisionFilter, model.hpp). A search keeps the pairs within each
// segment's search_reach, so that the next few (a step's substeps) can run the narrowphase on
// them alone (find_kept_pairs) and get the same contacts, as long as no segment outruns it.
//
// The narrowphase runs in blocks (of candidate pairs, or of limbs for the static tree's
// queries), on a BlockRunner's threads when one is given: each block writes only its own lists,
// joined in block order, so the contacts and the kept pairs are the serial search's to the bit
// on any number of threads. The sweep and prune itself runs on the calling thread.
//
// A contact is reported while the surfaces are closer than a margin, not only when they overlap
// (speculative contacts, as Box2D and Jolt do): a method that holds C ≥ 0 through the step then
// catches what would pass through between two detections. Its normal points from the second
// shape to the first, and the separation C = n·(p_first − p_second) − (r_first + r_second) is
// linear in the limbs' end points at fixed axial parameters — what the particle method
// projects, and what the rigid methods answer with impulses at `point`.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/geometry/broadphase.hpp"
#include "limber/kernel/geometry/shape_pairs.hpp"
#include "limber/kernel/geometry/static_geometry.hpp"
#include "limber/kernel/geometry/time_of_impact.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/threading/block_runner.hpp"

namespace limber {

/// LimbContact::second for a contact with static geometry.
inline constexpr std::uint32_t kStaticShape = 0xFFFFFFFFu;

/// A limb as collision sees it this step: the segment head → tail and its radius. A box or an
/// ellipsoid (its Model shape, which LimbCollisions keeps): head = tail = its centre, radius its
/// bounding_radius, and `orientation` its shape frame.
struct LimbSegment {
  Eigen::Vector3d head = Eigen::Vector3d::Zero();  ///< m, world
  Eigen::Vector3d tail = Eigen::Vector3d::Zero();  ///< m, world
  double radius = 0;                               ///< m
  /// m, ≥ 0: its own speculative margin, added to find()'s (how far it may move before the next
  /// contacts are made), so one fast limb widens its own search and not every pair's.
  double reach = 0;
  /// m, ≥ reach: how far it may move before the next broadphase search; find() keeps the pairs
  /// within it for find_kept_pairs() (0: reach).
  double search_reach = 0;
  /// Unit, shape frame → world: a box's or ellipsoid's (body orientation × Shape::rotation);
  /// unused for capsules, cylinders and balls.
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// A segment's shape in the world: a box or an ellipsoid (`shape`, its Model shape) about the
/// segment's centre in its orientation; any other limb (a cylinder too) and a ball the capsule of
/// its segment.
PlacedShape placed_shape(const Shape& shape, const LimbSegment& segment);

/// Two shapes closer than the margin. For a limb–limb contact, first < second (Model body
/// indices); against static geometry, second == kStaticShape and `collider` names it.
struct LimbContact {
  std::uint32_t first = 0;
  std::uint32_t second = kStaticShape;
  std::uint32_t collider = 0;   ///< Model::colliders index (static contacts)
  std::uint32_t triangle = 0;   ///< the mesh triangle (mesh colliders)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, from second towards first
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    ///< m, world: midway between the surfaces
  double separation = 0;     ///< m, < 0 overlapping (depth −separation)
  double axial_first = 0;    ///< where on first's segment: 0 at the head, 1 at the tail (0 for a box or ellipsoid)
  double axial_second = 0;   ///< the same on second's (limb–limb)
  std::uint32_t feature = 0; ///< a manifold point's id (manifolds.hpp): the features that touch; 0 for capsule pairs
  /// For static contacts: the static surface's point is fixed, and C = n·p_first − offset with
  /// offset = n·(static surface point) + r_first (m). Unused for limb–limb.
  double offset = 0;
  double friction = 0, restitution = 0;
};

/// What collides with what, fixed at compile: the bodies' filters, the pairs excluded (joined or
/// overlapping at the Model's poses), the static geometry in its tree. Holds the broadphase's
/// buffers, so a step that finds no more pairs than an earlier one allocates nothing.
class LimbCollisions {
 public:
  LimbCollisions() = default;
  /// Builds from `model` (its bodies, joints, colliders and Settings::limb_friction).
  explicit LimbCollisions(const Model& model);

  /// The shape segment `s` collides as: its Model body's (a ball's: a capsule of length 0).
  const Shape& shape(std::size_t s) const { return shapes_[s]; }

  /// Whether the model has anything to collide beyond the ground, the bounds and the balls'
  /// hits on limbs: a limb pair or a ball pair the filters allow, or a static collider. When
  /// false, find() does nothing.
  bool active() const { return active_; }

  /// The contacts within `margin` (m, ≥ 0: separation ≤ margin) among `limbs` — one per Model
  /// body, in order, then one per ball (head = tail = its centre): a ball meets static geometry
  /// and the other balls here, and limbs through its own path (contacts.hpp,
  /// rigid_contacts.hpp) — into `out` (cleared first), ordered by (first, second, collider,
  /// triangle, axial_first, feature): the same list whatever the broadphase's order, so a
  /// method's result is the same bits run to run. Up to three contacts per capsule limb and
  /// static shape (a limb lying on a face touches it with both ends; one across an edge, at the
  /// edge too); one per capsule pair, or two for capsules lying along each other (within 15° of
  /// parallel: the ends of their shared length); up to four (a manifold) for a pair with a box
  /// or an ellipsoid.
  /// A pair is tested only when at least one of its segments is `awake` (one flag per segment;
  /// static geometry is never awake). A contact's restitution is the larger of its two sides'
  /// (a ball's, a collider's; a limb has none). The narrowphase runs on `runner`'s threads when
  /// given and there are two blocks or more (waking its helpers for that stage if they sleep),
  /// with the same result. Throws std::invalid_argument when `limbs` or `awake` has the wrong size.
  void find(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake, double margin,
            std::vector<LimbContact>& out, BlockRunner* runner = nullptr);

  /// find()'s contacts without the broadphase: the same narrowphase over the pairs the last
  /// find() kept — pairs of segments, and of a segment and a static primitive, whose bounding
  /// spheres were within margin + their search_reach — at `limbs` now (their reach), the same
  /// contacts find() would give. That holds while every segment's move since the search (the
  /// larger of its ends' moves, and of its bounding sphere's centre move plus its growth) plus
  /// its reach now is within the search_reach it had: otherwise this returns false and finds
  /// nothing (call find()). `awake` must be the search's. candidate_pairs() is then 0.
  /// `runner` as for find().
  bool find_kept_pairs(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake, double margin,
                       std::vector<LimbContact>& out, BlockRunner* runner = nullptr);

  /// The deepest overlap among `limbs` now, between limbs and static geometry and between limbs
  /// — the run summary's measure (every method alike): its contact (depth −separation > 0), or a
  /// contact of separation 0 when nothing overlaps.
  LimbContact deepest_overlap(std::span<const LimbSegment> limbs);

  /// The pairs of segments the last find()'s sweep-and-prune broadphase gave (limb–limb and
  /// ball–ball, before the awake, filter and bounding-sphere tests; 0 when the model has no
  /// such pair to test). Static geometry's tree queries are not counted.
  std::size_t candidate_pairs() const { return candidate_pairs_; }

  /// Continuous collision against the static geometry (time_of_impact.hpp): segment `segment`'s
  /// sphere (the ball's, head = tail) of `radius` (m) moving from `from` to `to` (m, world) —
  /// its first touch of a static primitive its filter meets that needs answering there
  /// (answer_at_touch), among the primitives it does not overlap at `from` by more than
  /// kSweptSlop radii (deeper ones are the push-out's). Ties go to the tree's fixed order. No
  /// allocation.
  SweptTouch first_static_touch(std::uint32_t segment, const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius) const;

  /// The balls' own candidate search (broadphase.hpp), kept here with the other buffers every
  /// method's state holds: contacts.cpp and rigid_contacts.cpp fill it and read it each step.
  /// Reserved at construction for a few candidates per ball.
  BallCandidates& ball_candidates() { return ball_candidates_; }

  /// Pairs the constructor examined: pairs of distinct collision filters checked, and box pairs
  /// the sweep for overlaps at the Model's poses compared — its work, which grows with the
  /// bodies and not their square (a count for tests, instead of a time).
  std::uint64_t set_up_comparisons() const { return set_up_comparisons_; }
  /// Box pairs the broadphase compared over every find() so far (and the set-up's sweep): the
  /// search's work, for tests and benchmarks.
  std::uint64_t comparisons() const { return broadphase_.comparisons(); }

 private:
  /// Adds the pairs joints join to excluded_ (welded groups as one body).
  void exclude_joined_pairs(const Model& model);
  // A value type (states are copied): no shared buffers.
  // One narrowphase block's output: its contacts and the pairs it kept (limb pairs, or (segment,
  // primitive) pairs), each block's own, so blocks run on any thread.
  struct Block {
    std::vector<LimbContact> contacts;
    std::vector<CandidatePair> kept;
  };
  // A narrowphase pass in blocks: the first pair_blocks over `pairs` (a search's candidates, or
  // the kept limb pairs), the rest over the segments' static queries (a search) or `static_pairs`
  // (the kept ones). run() is a BlockRunner::BlockFunction.
  struct Narrowphase {
    const LimbCollisions* collisions = nullptr;
    std::span<const LimbSegment> limbs;
    std::span<const std::uint8_t> awake;
    double margin = 0;
    bool search = false, keep = false;
    std::span<const CandidatePair> pairs, static_pairs;
    std::size_t pair_blocks = 0, static_blocks = 0;
    Block* blocks = nullptr;  // run_narrowphase's
    static double run(const void* context, std::size_t index);
  };
  // find(), keeping its pairs for find_kept_pairs() or not (deepest_overlap).
  void search(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake, double margin,
              std::vector<LimbContact>& out, bool keep, BlockRunner* runner);
  void check_sizes(std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake) const;
  // Runs `pass`'s blocks, their contacts into `out` (and, when `keep`, their kept pairs into the
  // kept lists) in block order — straight in on one thread, else joined from the blocks' own
  // lists — and sorts `out`.
  void run_narrowphase(const Narrowphase& pass, std::vector<LimbContact>& out, bool keep, BlockRunner* runner);
  // Block `index` of `pass`: its contacts appended to `contacts`, its kept pairs to `kept`.
  void run_block(const Narrowphase& pass, std::size_t index, std::vector<LimbContact>& contacts, std::vector<CandidatePair>& kept) const;
  // One block of a search: its candidate pairs, filtered and tested.
  void search_limb_pairs(std::span<const CandidatePair> pairs, std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake,
                         double margin, bool keep, std::vector<LimbContact>& contacts, std::vector<CandidatePair>& kept) const;
  // One block of a search: segments [begin, end)'s queries of the static tree.
  void search_static(std::uint32_t begin, std::uint32_t end, std::span<const LimbSegment> limbs, std::span<const std::uint8_t> awake,
                     double margin, bool keep, std::vector<LimbContact>& contacts, std::vector<CandidatePair>& kept) const;
  // The narrowphase of one pair found: its contacts within margin + the segments' reach.
  void add_limb_pair(std::uint32_t i, std::uint32_t j, std::span<const LimbSegment> limbs, double margin,
                     std::vector<LimbContact>& out) const;
  void add_static_pair(std::uint32_t s, const LimbSegment& limb, const StaticPrimitive& primitive, double margin,
                       std::vector<LimbContact>& out) const;
  bool excluded(std::uint32_t first, std::uint32_t second) const;
  // Whether two segments' shapes overlap (the Model's poses: such a pair is excluded).
  bool overlapping(std::uint32_t first, std::uint32_t second, std::span<const LimbSegment> limbs) const;
  // Whether some pair of limbs (or of balls) left after the exclusions has filters that collide.
  bool some_pair_tested(bool balls);
  // Whether a search tests segments first < second: limb–limb or ball–ball, filters allowing.
  bool pair_tested(std::uint32_t first, std::uint32_t second) const;

  bool active_ = false;
  bool limb_pairs_ = false;                 // some limb pair the filters allow and no exclusion removes
  std::uint32_t limb_count_ = 0;            // Model bodies; the balls are the segments after them
  double limb_friction_ = 0;
  std::vector<CollisionFilter> filters_;    // per segment (a ball: the default filter)
  std::vector<Shape> shapes_;               // per segment: the Model body's (a ball: a capsule of length 0)
  std::vector<double> restitution_;         // per segment: a ball's, 0 for a limb
  std::vector<CandidatePair> excluded_;     // sorted: joined, or overlapping at the Model's poses
  std::vector<std::uint32_t> excluded_begin_;  // segment s's exclusions with later segments: excluded_[excluded_begin_[s], excluded_begin_[s + 1])
  StaticTree statics_;
  SweepAndPrune broadphase_;
  std::vector<Aabb> boxes_;                 // per segment, this call's
  std::vector<CandidatePair> kept_limb_pairs_;    // find()'s pairs within the search reach
  std::vector<CandidatePair> kept_static_pairs_;  // (segment, StaticTree primitive) within the search reach
  std::vector<LimbSegment> searched_;             // the segments find() kept its pairs for
  std::vector<Block> blocks_;               // the narrowphase's on threads, kept between calls
  std::vector<LimbContact> scratch_;        // deepest_overlap's contacts
  std::vector<std::uint8_t> all_awake_;     // deepest_overlap's flags
  BallCandidates ball_candidates_;
  std::uint64_t set_up_comparisons_ = 0;
  std::size_t candidate_pairs_ = 0;         // the last find()'s broadphase pairs
};

}  // namespace limber
