// libccd against FCL on the general convex pairs limber will collide (bench/collision.md,
// "Convex pairs: libccd against FCL"). Sphere, capsule, box, ellipsoid, cylinder and a 30-point
// convex hull at the sizes of a humanoid's limbs and props (2–30 cm, SI units), eight pairs,
// each timed on the same 256 fixed-seed relative poses: half overlapping (0.2–10 mm along the
// line of centres), half separated (0.2–20 mm along it).
//
// Contenders, time per pair (the counter per_pair; items_per_second is its inverse):
//   ccd_gjk_intersect    libccd ccdGJKIntersect, boolean
//   ccd_gjk_epa          libccd ccdGJKPenetration (GJK, then EPA): depth, direction, point
//   ccd_gjk_epa_fine     the same, epa_tolerance 10⁻¹⁰ m² in place of 10⁻⁶ (see make_ccd)
//   ccd_mpr              libccd ccdMPRPenetration (what MuJoCo calls)
//   fcl_libccd, fcl_indep   fcl::collide, one contact, gjk_solver_type GST_LIBCCD or GST_INDEP
//   fcl_dist_libccd, fcl_dist_indep   fcl::distance, on the 128 separated poses only
// libccd runs at FCL's GST_LIBCCD settings (500 iterations, tolerances 10⁻⁶); FCL at its defaults.
// FCL's box–box and sphere–box contacts are its own closed forms, whichever solver; its
// GST_LIBCCD contact on the other pairs is libccd's MPR. FCL 0.7.0's GST_INDEP contact on the
// other pairs comes with its depth negated and its normal in o1's frame (its
// gjk_solver_indep-inl.h); it is reported here as returned — undone, its depth is still mm off.
//
// Before timing it prints the agreement (not timed; half a minute): for each pose, each library's hit, depth and
// normal against a reference — for box–box the exact separating-axis depth (15 axes), for every
// pair the minimum over unit directions n of the overlap along n, h_A(n) + h_B(−n) (h the exact
// support function), searched from 2000 directions, both shapes' faces and edges and each
// library's normal, then refined. The separated poses' reference distance is the same search's
// maximum of −(h_A(n) + h_B(−n)).
//   build/bench/convex_pairs --timing_only --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//   build/bench/convex_pairs --agreement_only
#include <benchmark/benchmark.h>
#include <ccd/ccd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/ellipsoid.h>
#include <fcl/geometry/shape/sphere.h>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

enum class Kind { sphere, capsule, box, ellipsoid, cylinder, hull };

// size, m: sphere (r); capsule and cylinder (r, half length along z); box (half extents);
// ellipsoid (radii). A hull has its vertices in its own frame.
struct Shape {
  const char* name;
  Kind kind;
  Vector3d size;
  std::vector<Vector3d> vertices;
  std::shared_ptr<fcl::CollisionGeometryd> fcl;
  // Flat faces' normals and straight edges' directions, own frame: with the other shape's, the
  // separating-axis candidates, exact for two polyhedra.
  std::vector<Vector3d> face_normals{}, edges{};
};

Vector3d local_support(const Shape& s, const Vector3d& d) {
  const double sz = d.z() >= 0 ? 1.0 : -1.0;
  switch (s.kind) {
    case Kind::sphere: {
      const double n = d.norm();
      return n > 0 ? Vector3d(s.size[0] / n * d) : Vector3d(s.size[0], 0, 0);
    }
    case Kind::capsule: {
      const double n = d.norm();
      Vector3d v = n > 0 ? Vector3d(s.size[0] / n * d) : Vector3d(s.size[0], 0, 0);
      v.z() += sz * s.size[1];
      return v;
    }
    case Kind::box:
      return {d.x() >= 0 ? s.size.x() : -s.size.x(), d.y() >= 0 ? s.size.y() : -s.size.y(), sz * s.size.z()};
    case Kind::ellipsoid: {
      const Vector3d ad = s.size.cwiseProduct(d);
      const double n = ad.norm();
      return n > 0 ? Vector3d(s.size.cwiseProduct(ad) / n) : Vector3d(s.size.x(), 0, 0);
    }
    case Kind::cylinder: {
      const double n = std::hypot(d.x(), d.y());
      return n > 0 ? Vector3d(s.size[0] * d.x() / n, s.size[0] * d.y() / n, sz * s.size[1]) : Vector3d(s.size[0], 0, sz * s.size[1]);
    }
    case Kind::hull: {
      std::size_t best = 0;
      double best_dot = -1e300;
      for (std::size_t i = 0; i < s.vertices.size(); ++i) {
        const double dot = s.vertices[i].dot(d);
        if (dot > best_dot) best_dot = dot, best = i;
      }
      return s.vertices[best];
    }
  }
  return Vector3d::Zero();
}

// A shape at a pose: libccd's object (its callbacks get a pointer to it).
struct Posed {
  const Shape* shape;
  Matrix3d rotation;
  Vector3d position;
  Vector3d support(const Vector3d& d) const { return rotation * local_support(*shape, rotation.transpose() * d) + position; }
  double h(const Vector3d& n) const { return n.dot(support(n)); }  // support function, m
};

void ccd_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const Vector3d v = static_cast<const Posed*>(obj)->support(Vector3d(dir->v[0], dir->v[1], dir->v[2]));
  out->v[0] = v.x(), out->v[1] = v.y(), out->v[2] = v.z();
}

void ccd_center(const void* obj, ccd_vec3_t* out) {
  const Vector3d& p = static_cast<const Posed*>(obj)->position;
  out->v[0] = p.x(), out->v[1] = p.y(), out->v[2] = p.z();
}

// FCL's GST_LIBCCD settings (GJKSolver_libccd: 500 iterations, tolerances 10⁻⁶); libccd's own
// defaults stop at 10⁻⁴. libccd's EPA stops when s·w − |w|² < epa_tolerance (w its nearest point
// to the origin, |w| the depth; s the new support point), m²: the depth's error is up to
// about epa_tolerance / depth, 0.2 mm at 5 mm deep and 10⁻⁶ — hence the "fine" setting, 10⁻¹⁰ m².
ccd_t make_ccd(double epa_tolerance = 1e-6) {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd.support2 = ccd_support;
  ccd.center1 = ccd.center2 = ccd_center;
  ccd.max_iterations = 500;
  ccd.mpr_tolerance = 1e-6;
  ccd.epa_tolerance = epa_tolerance;
  return ccd;
}
constexpr double fine_epa_tolerance = 1e-10;  // m²

// 30 points on an ellipsoid (7, 6, 5 cm): all are hull vertices. Faces by brute force (every
// triple with all points on one side), which FCL's Convex needs and libccd does not.
Shape make_hull() {
  Shape s{"hull", Kind::hull, Vector3d(0.07, 0.06, 0.05), {}, nullptr, {}, {}};
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  for (int i = 0; i < 30; ++i) s.vertices.push_back(s.size.cwiseProduct(Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized()));
  const int n = static_cast<int>(s.vertices.size());
  auto faces = std::make_shared<std::vector<int>>();
  int face_count = 0;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        const Vector3d normal = (s.vertices[j] - s.vertices[i]).cross(s.vertices[k] - s.vertices[i]);
        int above = 0, below = 0;
        for (int m = 0; m < n; ++m) {
          const double side = normal.dot(s.vertices[m] - s.vertices[i]);
          above += side > 1e-12, below += side < -1e-12;
        }
        if (above > 0 && below > 0) continue;
        // Counter-clockwise seen from outside (the centroid, the origin, is below).
        const bool outward = normal.dot(s.vertices[i]) > 0;
        faces->insert(faces->end(), {3, i, outward ? j : k, outward ? k : j});
        ++face_count;
        s.face_normals.push_back(normal.normalized());
        for (const auto& [p, q] : {std::pair{i, j}, std::pair{j, k}, std::pair{k, i}}) s.edges.push_back((s.vertices[q] - s.vertices[p]).normalized());
      }
  auto verts = std::make_shared<std::vector<Vector3d>>(s.vertices);
  s.fcl = std::make_shared<fcl::Convexd>(verts, face_count, faces);
  return s;
}

std::vector<Shape> make_shapes() {
  std::vector<Shape> shapes;
  const std::vector<Vector3d> axes = {Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitZ()};
  shapes.push_back({"sphere", Kind::sphere, Vector3d(0.06, 0, 0), {}, std::make_shared<fcl::Sphered>(0.06), {}, {}});
  shapes.push_back({"capsule", Kind::capsule, Vector3d(0.04, 0.12, 0), {}, std::make_shared<fcl::Capsuled>(0.04, 0.24)});
  shapes.push_back({"box", Kind::box, Vector3d(0.10, 0.06, 0.03), {}, std::make_shared<fcl::Boxd>(0.20, 0.12, 0.06)});
  shapes.push_back({"box", Kind::box, Vector3d(0.15, 0.04, 0.02), {}, std::make_shared<fcl::Boxd>(0.30, 0.08, 0.04)});  // a plank
  shapes.push_back({"ellipsoid", Kind::ellipsoid, Vector3d(0.08, 0.05, 0.03), {}, std::make_shared<fcl::Ellipsoidd>(0.08, 0.05, 0.03)});
  shapes.push_back({"cylinder", Kind::cylinder, Vector3d(0.05, 0.10, 0), {}, std::make_shared<fcl::Cylinderd>(0.05, 0.20)});
  shapes.push_back(make_hull());
  shapes.push_back(make_hull());
  for (const int i : {2, 3}) shapes[i].face_normals = shapes[i].edges = axes;
  shapes[1].edges = {Vector3d::UnitZ()};  // the capsule's segment
  shapes[5].face_normals = shapes[5].edges = {Vector3d::UnitZ()};  // the cylinder's caps and sides
  return shapes;
}
enum ShapeIndex { sphere, capsule, box, plank, ellipsoid, cylinder, hull, hull2 };

struct Pose {
  Posed a, b;
  fcl::Transform3d ta, tb;
  bool overlapping;     // as made: moved along the line of centres past or short of touching
  double ref_depth;     // overlapping: reference penetration depth, m; separated: reference distance, m
  Vector3d ref_normal;  // overlapping: the direction to move b by ref_depth to separate, unit
};

struct PairSet {
  std::string name;
  std::vector<Pose> poses;
  std::vector<Pose> separated;  // fcl::distance's poses (with their references once computed)
};

// Overlap along n: how far b must move along n to leave a, m (negative: n separates them by that).
double overlap(const Posed& a, const Posed& b, const Vector3d& n) { return a.h(n) + b.h(-n); }

// min over unit n of overlap(n): the penetration depth when positive, minus the distance when
// negative (the separating-axis theorem for convex sets). Searched from the given starts, the
// faces' normals and the edges' cross products of both shapes (exact for two polyhedra), along
// each crease of the support functions (n ⊥ an edge: a pattern search stalls there, and a curved
// shape against a box's edge has its minimum on one), refined by a shrinking pattern search.
std::pair<double, Vector3d> min_overlap(const Posed& a, const Posed& b, std::vector<Vector3d> starts) {
  for (const Posed* s : {&a, &b})
    for (const Vector3d& n : s->shape->face_normals) starts.push_back(s->rotation * n), starts.push_back(-(s->rotation * n));
  for (const Vector3d& ea : a.shape->edges)
    for (const Vector3d& eb : b.shape->edges) {
      const Vector3d c = (a.rotation * ea).cross(b.rotation * eb);
      if (c.norm() > 1e-9) starts.push_back(c.normalized()), starts.push_back(-c.normalized());
    }
  Vector3d best = starts.front();
  double best_value = overlap(a, b, best);
  for (const Vector3d& n : starts) {
    const double v = overlap(a, b, n);
    if (v < best_value) best_value = v, best = n;
  }
  for (const Posed* s : {&a, &b})
    for (const Vector3d& e : s->shape->edges) {
      const Vector3d axis = s->rotation * e, t1 = axis.unitOrthogonal(), t2 = axis.cross(t1);
      const auto on_crease = [&](double phi) { return Vector3d(std::cos(phi) * t1 + std::sin(phi) * t2); };
      const int samples = 720;
      const double d_phi = 2 * std::numbers::pi / samples;
      int k_best = 0;
      double v_best = 1e300;
      for (int k = 0; k < samples; ++k) {
        const double v = overlap(a, b, on_crease(k * d_phi));
        if (v < v_best) v_best = v, k_best = k;
      }
      double lo = (k_best - 1) * d_phi, hi = (k_best + 1) * d_phi;  // golden section in the bracket
      const double g = (std::sqrt(5.0) - 1) / 2;
      while (hi - lo > 1e-13) {
        const double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
        if (overlap(a, b, on_crease(x1)) < overlap(a, b, on_crease(x2))) {
          hi = x2;
        } else {
          lo = x1;
        }
      }
      const Vector3d n = on_crease(0.5 * (lo + hi));
      const double v = overlap(a, b, n);
      if (v < best_value) best_value = v, best = n;
    }
  for (double step = 0.05; step > 1e-12;) {
    const Vector3d t1 = best.unitOrthogonal(), t2 = best.cross(t1);
    bool improved = false;
    for (int k = 0; k < 64; ++k) {  // many: at a crease of a box's support function the way down is narrow
      const double turn = k * std::numbers::pi / 32;
      const Vector3d n = (best + step * (std::cos(turn) * t1 + std::sin(turn) * t2)).normalized();
      const double v = overlap(a, b, n);
      if (v < best_value) best_value = v, best = n, improved = true;
    }
    if (!improved) step *= 0.5;
  }
  return {best_value, best};
}

std::vector<Vector3d> sphere_directions(int count) {  // Fibonacci lattice
  std::vector<Vector3d> dirs;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1 - (i + 0.5) * 2.0 / count, r = std::sqrt(1 - z * z);
    dirs.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return dirs;
}

// Box–box: the minimum overlap over the 15 separating axes is the exact penetration depth.
std::pair<double, Vector3d> sat_box_box(const Posed& a, const Posed& b) {
  std::vector<Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.rotation.col(i)), axes.push_back(b.rotation.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vector3d c = a.rotation.col(i).cross(b.rotation.col(j));
      if (c.norm() > 1e-9) axes.push_back(c.normalized());
    }
  double depth = 1e300;
  Vector3d normal;
  for (const Vector3d& axis : axes)
    for (const Vector3d& n : {axis, Vector3d(-axis)}) {
      const double o = overlap(a, b, n);
      if (o < depth) depth = o, normal = n;
    }
  return {depth, normal};
}

Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> gauss;
  return Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized().toRotationMatrix();
}

fcl::Transform3d to_fcl(const Posed& p) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.linear() = p.rotation;
  t.translation() = p.position;
  return t;
}

// 256 poses: random orientations and a random direction u from a's centre; b's centre on u at
// the touching distance (bisection on libccd MPR's boolean, to 10⁻¹² m) less 0.2–10 mm or plus
// 0.2–20 mm. Fixed seed per pair: every library gets the same poses.
PairSet make_pairs(const std::string& name, const Shape& sa, const Shape& sb, unsigned seed) {
  PairSet set{name, {}, {}};
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> in(0.0002, 0.010), out(0.0002, 0.020);
  const ccd_t ccd = make_ccd();
  for (int i = 0; i < 256; ++i) {
    Pose pose;
    pose.a = {&sa, random_rotation(rng), Vector3d::Zero()};
    pose.b = {&sb, random_rotation(rng), Vector3d::Zero()};
    const Vector3d u = Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    double lo = 0, hi = 1.0;
    while (hi - lo > 1e-12) {
      const double mid = 0.5 * (lo + hi);
      pose.b.position = mid * u;
      (ccdMPRIntersect(&pose.a, &pose.b, &ccd) ? lo : hi) = mid;
    }
    pose.overlapping = i % 2 == 0;
    pose.b.position = (pose.overlapping ? lo - in(rng) : hi + out(rng)) * u;
    pose.ta = to_fcl(pose.a);
    pose.tb = to_fcl(pose.b);
    set.poses.push_back(pose);
    if (!pose.overlapping) set.separated.push_back(pose);
  }
  return set;
}

std::vector<Shape> shapes;
std::vector<PairSet> sets;

// One library's answer on one pose, the normal turned to "move b along it to separate".
struct Answer {
  bool hit = false;
  double depth = 0;
  Vector3d normal = Vector3d::Zero();
};

Answer ccd_answer(const Pose& p, bool mpr, double epa_tolerance = 1e-6) {
  const ccd_t ccd = make_ccd(epa_tolerance);
  ccd_real_t depth;
  ccd_vec3_t dir, pos;
  const int r = mpr ? ccdMPRPenetration(&p.a, &p.b, &ccd, &depth, &dir, &pos) : ccdGJKPenetration(&p.a, &p.b, &ccd, &depth, &dir, &pos);
  if (r != 0) return {};
  return {true, depth, Vector3d(dir.v[0], dir.v[1], dir.v[2])};  // libccd: b moves by depth·dir
}

fcl::CollisionRequestd contact_request(fcl::GJKSolverType solver) {
  fcl::CollisionRequestd request(1, true);
  request.gjk_solver_type = solver;
  return request;
}

Answer fcl_answer(const Pose& p, fcl::GJKSolverType solver) {
  fcl::CollisionResultd result;
  fcl::collide(p.a.shape->fcl.get(), p.ta, p.b.shape->fcl.get(), p.tb, contact_request(solver), result);
  if (!result.isCollision() || result.numContacts() == 0) return {};
  const auto& c = result.getContact(0);
  return {true, c.penetration_depth, c.normal};  // FCL: the normal points from o1 to o2
}

double fcl_distance(const Pose& p, fcl::GJKSolverType solver) {
  fcl::DistanceRequestd request;
  request.gjk_solver_type = solver;
  fcl::DistanceResultd result;
  return fcl::distance(p.a.shape->fcl.get(), p.ta, p.b.shape->fcl.get(), p.tb, request, result);
}

Answer answer(const Pose& p, int library) {
  switch (library) {
    case 0: return ccd_answer(p, false);
    case 1: return ccd_answer(p, false, fine_epa_tolerance);
    case 2: return ccd_answer(p, true);
    case 3: return fcl_answer(p, fcl::GST_LIBCCD);
    default: return fcl_answer(p, fcl::GST_INDEP);
  }
}
constexpr int library_count = 5;
const char* const library_names[library_count] = {"libccd GJK/EPA", "libccd GJK/EPA, fine", "libccd MPR", "FCL GST_LIBCCD", "FCL GST_INDEP"};

std::vector<Answer> all_answers(const Pose& p) {
  std::vector<Answer> answers;
  for (int lib = 0; lib < library_count; ++lib) answers.push_back(answer(p, lib));
  return answers;
}

// The references: the search from 2000 directions, then again from each library's normal (a lower
// minimum there would mean the first search stopped in a local one: it prints how often).
void compute_references() {
  const std::vector<Vector3d> dirs = sphere_directions(2000);
  for (PairSet& set : sets)
    for (Pose& p : set.poses) {
      std::tie(p.ref_depth, p.ref_normal) = min_overlap(p.a, p.b, dirs);
      if (!p.overlapping) p.ref_depth = -p.ref_depth;
    }
  int lowered = 0;
  double most = 0;
  for (PairSet& set : sets)
    for (Pose& p : set.poses) {
      std::vector<Vector3d> starts = {p.ref_normal};
      for (const Answer& x : all_answers(p))
        if (x.hit) starts.push_back(x.normal.normalized());
      const auto [value, normal] = min_overlap(p.a, p.b, starts);
      const double before = p.overlapping ? p.ref_depth : -p.ref_depth;
      if (value < before - 1e-12) {
        ++lowered, most = std::max(most, before - value);
        p.ref_depth = p.overlapping ? value : -value, p.ref_normal = normal;
      }
    }
  for (PairSet& set : sets) {
    set.separated.clear();
    for (const Pose& p : set.poses)
      if (!p.overlapping) set.separated.push_back(p);
  }
  std::printf("References lowered by a library's normal: %d of %zu poses, by at most %.2e m\n", lowered, sets.size() * 256, most);
}

double angle_deg(const Vector3d& a, const Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / std::numbers::pi;
}

void print_agreement() {
  std::printf("Agreement on the 128 overlapping poses of each pair, against the reference (see the file's head).\n");
  std::printf("| pair | library | misses | false hits (of 128 separated) | max abs depth error (m) | median abs depth error (m) | depth off > 0.1 mm | max normal angle (deg) | normal off > 5° |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const PairSet& set : sets) {
    double spread_depth = 0, spread_angle = 0;
    for (int lib = 0; lib < library_count; ++lib) {
      int misses = 0, false_hits = 0, off_depth = 0, off_normal = 0;
      double max_err = 0, max_angle = 0;
      std::vector<double> errs;
      for (const Pose& p : set.poses) {
        const Answer a = answer(p, lib);
        if (!p.overlapping) {
          false_hits += a.hit;
          continue;
        }
        if (!a.hit) {
          ++misses;
          std::printf("  miss: %s %s, reference depth %.3e m\n", set.name.c_str(), library_names[lib], p.ref_depth);
          continue;
        }
        const double err = std::abs(a.depth - p.ref_depth);
        errs.push_back(err);
        max_err = std::max(max_err, err);
        const double angle = angle_deg(a.normal, p.ref_normal);
        max_angle = std::max(max_angle, angle);
        off_depth += err > 1e-4, off_normal += angle > 5;
      }
      std::sort(errs.begin(), errs.end());
      std::printf("| %s | %s | %d | %d | %.2e | %.2e | %d | %.3g | %d |\n", set.name.c_str(), library_names[lib], misses, false_hits, max_err,
                  errs.empty() ? 0.0 : errs[errs.size() / 2], off_depth, max_angle, off_normal);
    }
    // The libraries among themselves: the widest spread of depth and normal on one pose.
    for (const Pose& p : set.poses) {
      if (!p.overlapping) continue;
      const std::vector<Answer> answers = all_answers(p);
      for (const Answer& x : answers)
        for (const Answer& y : answers)
          if (x.hit && y.hit) spread_depth = std::max(spread_depth, std::abs(x.depth - y.depth)), spread_angle = std::max(spread_angle, angle_deg(x.normal, y.normal));
    }
    std::printf("| %s | the five, widest spread on a pose | | | %.2e | | | %.3g | |\n", set.name.c_str(), spread_depth, spread_angle);
  }
  // The box–box reference against the exact separating-axis depth.
  double sat_gap = 0, sat_angle = 0;
  for (const Pose& p : sets.front().poses) {
    if (!p.overlapping) continue;
    const auto [depth, normal] = sat_box_box(p.a, p.b);
    sat_gap = std::max(sat_gap, std::abs(depth - p.ref_depth));
    sat_angle = std::max(sat_angle, angle_deg(normal, p.ref_normal));
  }
  std::printf("box_box: the searched reference against the 15-axis SAT depth: max %.2e m, %.3g deg\n", sat_gap, sat_angle);
  std::printf("\nfcl::distance on the 128 separated poses against the reference distance:\n| pair | solver | max abs error (m) | median (m) | off > 0.1 mm |\n|---|---|---:|---:|---:|\n");
  for (const PairSet& set : sets)
    for (const fcl::GJKSolverType solver : {fcl::GST_LIBCCD, fcl::GST_INDEP}) {
      std::vector<double> errs;
      for (const Pose& p : set.separated) errs.push_back(std::abs(fcl_distance(p, solver) - p.ref_depth));
      std::sort(errs.begin(), errs.end());
      const auto off = std::count_if(errs.begin(), errs.end(), [](double e) { return e > 1e-4; });
      std::printf("| %s | %s | %.2e | %.2e | %td |\n", set.name.c_str(), solver == fcl::GST_LIBCCD ? "GST_LIBCCD" : "GST_INDEP", errs.back(), errs[errs.size() / 2], off);
    }
  std::printf("\n");
}

void per_pair(benchmark::State& state, std::size_t pairs) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pairs));
  // Seconds a pair (the console prints it with its prefix: "541ns").
  state.counters["per_pair"] = benchmark::Counter(static_cast<double>(pairs), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void bm_ccd_gjk_intersect(benchmark::State& state, const PairSet* set) {
  const ccd_t ccd = make_ccd();
  for (auto _ : state) {
    int hits = 0;
    for (const Pose& p : set->poses) hits += ccdGJKIntersect(&p.a, &p.b, &ccd);
    benchmark::DoNotOptimize(hits);
  }
  per_pair(state, set->poses.size());
}

void bm_ccd_penetration(benchmark::State& state, const PairSet* set, bool mpr, double epa_tolerance) {
  const ccd_t ccd = make_ccd(epa_tolerance);
  for (auto _ : state) {
    double sum = 0;
    for (const Pose& p : set->poses) {
      ccd_real_t depth = 0;
      ccd_vec3_t dir, pos;
      if ((mpr ? ccdMPRPenetration(&p.a, &p.b, &ccd, &depth, &dir, &pos) : ccdGJKPenetration(&p.a, &p.b, &ccd, &depth, &dir, &pos)) == 0) sum += depth + dir.v[0] + pos.v[0];
    }
    benchmark::DoNotOptimize(sum);
  }
  per_pair(state, set->poses.size());
}

void bm_fcl_collide(benchmark::State& state, const PairSet* set, fcl::GJKSolverType solver) {
  const fcl::CollisionRequestd request = contact_request(solver);
  for (auto _ : state) {
    double sum = 0;
    for (const Pose& p : set->poses) {
      fcl::CollisionResultd result;
      if (fcl::collide(p.a.shape->fcl.get(), p.ta, p.b.shape->fcl.get(), p.tb, request, result) > 0) sum += result.getContact(0).penetration_depth;
    }
    benchmark::DoNotOptimize(sum);
  }
  per_pair(state, set->poses.size());
}

void bm_fcl_distance(benchmark::State& state, const PairSet* set, fcl::GJKSolverType solver) {
  fcl::DistanceRequestd request;
  request.gjk_solver_type = solver;
  for (auto _ : state) {
    double sum = 0;
    for (const Pose& p : set->separated) {
      fcl::DistanceResultd result;
      sum += fcl::distance(p.a.shape->fcl.get(), p.ta, p.b.shape->fcl.get(), p.tb, request, result);
    }
    benchmark::DoNotOptimize(sum);
  }
  per_pair(state, set->separated.size());
}

}  // namespace

int main(int argc, char** argv) {
  shapes = make_shapes();
  const std::array<std::pair<int, int>, 8> pairs = {{{box, plank}, {capsule, box}, {sphere, box}, {ellipsoid, box}, {cylinder, box}, {hull, box}, {hull, hull2}, {ellipsoid, capsule}}};
  const char* pair_names[] = {"box_box", "capsule_box", "sphere_box", "ellipsoid_box", "cylinder_box", "hull_box", "hull_hull", "ellipsoid_capsule"};
  for (std::size_t i = 0; i < pairs.size(); ++i) sets.push_back(make_pairs(pair_names[i], shapes[pairs[i].first], shapes[pairs[i].second], 1000 + static_cast<unsigned>(i)));

  // --agreement_only: the agreement, no timing; --timing_only: the timing (the references' search
  // takes half a minute).
  bool agreement_only = false, timing_only = false;
  for (int i = 1; i < argc; ++i) {
    agreement_only |= std::strcmp(argv[i], "--agreement_only") == 0;
    timing_only |= std::strcmp(argv[i], "--timing_only") == 0;
  }
  if (!timing_only) {
    compute_references();
    print_agreement();
  }
  if (agreement_only) return 0;

  for (const PairSet& set : sets) {
    const PairSet* s = &set;
    benchmark::RegisterBenchmark((set.name + "/ccd_gjk_intersect").c_str(), bm_ccd_gjk_intersect, s);
    benchmark::RegisterBenchmark((set.name + "/ccd_gjk_epa").c_str(), bm_ccd_penetration, s, false, 1e-6);
    benchmark::RegisterBenchmark((set.name + "/ccd_gjk_epa_fine").c_str(), bm_ccd_penetration, s, false, fine_epa_tolerance);
    benchmark::RegisterBenchmark((set.name + "/ccd_mpr").c_str(), bm_ccd_penetration, s, true, 1e-6);
    benchmark::RegisterBenchmark((set.name + "/fcl_libccd").c_str(), bm_fcl_collide, s, fcl::GST_LIBCCD);
    benchmark::RegisterBenchmark((set.name + "/fcl_indep").c_str(), bm_fcl_collide, s, fcl::GST_INDEP);
    benchmark::RegisterBenchmark((set.name + "/fcl_dist_libccd").c_str(), bm_fcl_distance, s, fcl::GST_LIBCCD);
    benchmark::RegisterBenchmark((set.name + "/fcl_dist_indep").c_str(), bm_fcl_distance, s, fcl::GST_INDEP);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
