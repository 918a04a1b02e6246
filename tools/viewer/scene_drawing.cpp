#include "tools/viewer/scene_drawing.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/geometry/bounding_volumes.hpp"

namespace limber::viewer {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Zero-radius limbs (thin rods) are drawn this thick, m.
constexpr float kThinnest = 0.006f;

Eigen::Isometry3f placement(const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation) {
  Eigen::Isometry3f p = Eigen::Isometry3f::Identity();
  p.linear() = orientation.cast<float>().toRotationMatrix();
  p.translation() = position.cast<float>();
  return p;
}

// Distinct hues for neighbouring bodies (golden-ratio steps), in linear RGB (the renderer shows
// them brighter, as sRGB); a sleeping body greyer.
Colour body_colour(std::size_t index, bool picked, bool sleeping) {
  if (picked) return {1.0f, 0.62f, 0.15f};
  const float hue = std::fmod(0.58f + 0.618034f * float(index), 1.0f);
  const float s = sleeping ? 0.35f : 0.75f, v = sleeping ? 0.55f : 0.7f;
  const float h6 = hue * 6, f = h6 - std::floor(h6);
  const float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (int(h6) % 6) {
    case 0: return {v, t, p};
    case 1: return {q, v, p};
    case 2: return {p, v, t};
    case 3: return {p, q, v};
    case 4: return {t, p, v};
    default: return {v, p, q};
  }
}

void add_line(std::vector<Line>& lines, const Eigen::Vector3d& from, const Eigen::Vector3d& to, Colour colour) {
  lines.push_back(Line{from.cast<float>(), to.cast<float>(), colour});
}

// A circle of `radius` about `centre` in the plane normal to `axis` (unit), as 32 segments.
void add_circle(std::vector<Line>& lines, const Eigen::Vector3d& centre, const Eigen::Vector3d& axis, double radius, Colour colour) {
  const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
  constexpr int kSegments = 32;
  for (int i = 0; i < kSegments; ++i) {
    const double a0 = 2 * kPi * i / kSegments, a1 = 2 * kPi * (i + 1) / kSegments;
    add_line(lines, centre + radius * (std::cos(a0) * u + std::sin(a0) * v), centre + radius * (std::cos(a1) * u + std::sin(a1) * v),
             colour);
  }
}

void add_cross(std::vector<Line>& lines, const Eigen::Vector3d& at, double size, Colour colour) {
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d d = size * Eigen::Vector3d::Unit(axis);
    add_line(lines, at - d, at + d, colour);
  }
}

// An arrow from `from` along `vector`, its head a quarter of its length (at most 8 cm).
void add_arrow(std::vector<Line>& lines, const Eigen::Vector3d& from, const Eigen::Vector3d& vector, Colour colour) {
  const double length = vector.norm();
  if (length == 0) return;
  const Eigen::Vector3d tip = from + vector, back = -vector / length, side = back.unitOrthogonal();
  const double head = std::min(0.25 * length, 0.08);
  add_line(lines, from, tip, colour);
  add_line(lines, tip, tip + head * (0.9 * back + 0.45 * side), colour);
  add_line(lines, tip, tip + head * (0.9 * back - 0.45 * side), colour);
}

void add_box_edges(std::vector<Line>& lines, const Eigen::Vector3d& low, const Eigen::Vector3d& high, Colour colour) {
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int corner = 0; corner < 4; ++corner) {
      Eigen::Vector3d from = low, to = low;
      from[a] = to[a] = (corner & 1) ? high[a] : low[a];
      from[b] = to[b] = (corner & 2) ? high[b] : low[b];
      to[axis] = high[axis];
      add_line(lines, from, to, colour);
    }
  }
}

void draw_bodies(const ViewState& view, DrawList& list) {
  const World& world = view.world();
  const std::vector<BodyId> bodies = world.bodies();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const Pose pose = world.pose(bodies[i]);
    const Shape& shape = world.body_description(bodies[i]).shape;
    Solid solid;
    if (has_half_extents(shape)) {  // in its own frame, turned from the body's by shape.rotation
      solid.kind = shape.type == ShapeType::box ? SolidKind::box : SolidKind::ellipsoid;
      solid.placement = placement(pose.position, pose.orientation * shape.rotation);
      solid.half_extents = shape.half_extents.cast<float>();
    } else {
      solid.kind = shape.type == ShapeType::capsule ? SolidKind::capsule : SolidKind::cylinder;
      solid.placement = placement(pose.position, pose.orientation);
      solid.radius = std::max(float(shape.radius), kThinnest);
      solid.half_length = float(0.5 * shape.length);
    }
    solid.colour = body_colour(i, view.picked() == i, world.sleeping(bodies[i]));
    list.solids.push_back(solid);
  }
  for (const BallId id : world.balls()) {
    Solid ball;
    ball.kind = SolidKind::sphere;
    ball.placement = placement(world.ball(id).position, Eigen::Quaterniond::Identity());
    ball.radius = float(world.model().balls[world.index(id)].radius);
    ball.colour = {0.85f, 0.16f, 0.14f};
    list.solids.push_back(ball);
  }
}

void draw_level(const Model& model, DrawList& list) {
  const Colour level{0.55f, 0.57f, 0.62f};
  for (const StaticCollider& collider : model.colliders) {
    if (collider.type == ColliderType::mesh) {
      TriangleSoup soup;
      soup.colour = level;
      for (const auto& triangle : collider.mesh.triangles) {
        for (const std::uint32_t v : triangle) soup.vertices.push_back(collider.mesh.vertices[v].cast<float>());
      }
      list.meshes.push_back(std::move(soup));
      continue;
    }
    Solid solid;
    solid.kind = collider.type == ColliderType::box ? SolidKind::box : SolidKind::capsule;
    solid.placement = placement(collider.position, collider.orientation);
    solid.half_extents = collider.half_extents.cast<float>();
    solid.radius = float(collider.radius), solid.half_length = float(0.5 * collider.length);
    solid.colour = level;
    solid.casts_shadow = false;
    list.solids.push_back(solid);
  }
  if (model.bounds) add_box_edges(list.lines, model.bounds->min, model.bounds->max, {0.3f, 0.3f, 0.35f});
}

// A limb's size to measure a joint's gap against, m: its length, a box's or ellipsoid's longest
// extent (its length is 0).
double limb_size(const Shape& shape) { return has_half_extents(shape) ? 2 * shape.half_extents.maxCoeff() : shape.length; }

void draw_joint_gaps(const World& world, DrawList& list) {
  const Model& model = world.model();
  const std::vector<BodyId> bodies = world.bodies();
  for (const Joint& joint : model.joints) {
    const Pose out = world.pose(bodies[joint.outboard]);
    const Eigen::Vector3d b = out.position + out.orientation * joint.outboard_anchor;
    Eigen::Vector3d a = joint.inboard_anchor;
    double length = limb_size(model.bodies[joint.outboard].shape);
    if (joint.inboard != kWorld) {
      const Pose in = world.pose(bodies[joint.inboard]);
      a = in.position + in.orientation * joint.inboard_anchor;
      length = 0.5 * (length + limb_size(model.bodies[joint.inboard].shape));
    }
    const Colour colour = gap_colour((a - b).norm() / std::max(length, 1e-9));
    add_line(list.on_top, a, b, colour);
    add_cross(list.on_top, b, 0.015, colour);
  }
}

void draw_overlays(const ViewState& view, SceneDrawer& drawer, DrawList& list) {
  const World& world = view.world();
  const Overlays& overlays = view.overlays;
  if (overlays.bounding_volumes) {
    for (const BodyId id : world.bodies()) {
      const Pose pose = world.pose(id);
      const BoundingSphere sphere = limb_sphere(world.body_description(id).shape, pose.position, pose.orientation);
      for (int axis = 0; axis < 3; ++axis) add_circle(list.lines, sphere.centre, Eigen::Vector3d::Unit(axis), sphere.radius, {0.2f, 0.45f, 0.95f});
    }
  }
  if (overlays.contacts) {
    for (const ShownContact& contact : drawer.contacts(world)) {
      add_cross(list.on_top, contact.point, 0.01, {1.0f, 0.9f, 0.1f});
      add_line(list.on_top, contact.point, contact.point + 0.12 * contact.normal, {1.0f, 0.9f, 0.1f});
    }
  }
  if (overlays.joint_gaps) draw_joint_gaps(world, list);
  if (overlays.centre_of_mass) {
    const Eigen::Vector3d centre = world.observe().body_centre_of_mass;
    add_cross(list.on_top, centre, 0.05, {1, 1, 1});
    const std::deque<Eigen::Vector3d>& path = view.history().path;
    for (std::size_t i = 1; i < path.size(); ++i) add_line(list.on_top, path[i - 1], path[i], {0.95f, 0.95f, 0.95f});
    if (world.model().ground) add_line(list.lines, centre, {centre.x(), centre.y(), world.model().ground->height}, {1, 1, 1});
  }
  if (overlays.forces) {
    // 1 m of arrow per 10 g of acceleration of the limb it acts on: pushes and drags of any
    // limb read alike.
    for (const auto& [point, force] : view.last_loads()) {
      const double mass = view.picked() ? world.body_description(world.bodies()[*view.picked()]).mass : 1.0;
      add_arrow(list.on_top, point, force / (mass * 98.1), {0.1f, 0.95f, 0.4f});
    }
    if (view.drag()) {
      const auto& drag = *view.drag();
      const Pose pose = world.pose(world.bodies()[drag.body]);
      add_line(list.on_top, pose.position + pose.orientation * drag.local_point, drag.target, {1, 1, 1});
    }
  }
}

}  // namespace

Colour gap_colour(double relative_gap) {
  const double x = std::clamp((std::log10(std::max(relative_gap, 1e-12)) + 4) / 3, 0.0, 1.0);  // 1e-4 → 0, 1e-1 → 1
  return x < 0.5 ? Colour{float(2 * x), 0.85f, 0.1f} : Colour{1.0f, float(0.85 * (2 - 2 * x)), 0.1f};
}

void SceneDrawer::refresh(const World& world) {
  const Model& model = world.model();
  if (model_ == &model && bodies_ == model.bodies.size() && balls_ == model.balls.size() && colliders_ == model.colliders.size()) return;
  model_ = &model, bodies_ = model.bodies.size(), balls_ = model.balls.size(), colliders_ = model.colliders.size();
  collisions_ = LimbCollisions(model);
}

const std::vector<ShownContact>& SceneDrawer::contacts(const World& world) {
  refresh(world);
  contacts_.clear();
  world.segments(segments_);
  const Model& model = world.model();
  if (collisions_.active()) {
    awake_.assign(segments_.size(), 1);
    collisions_.find(segments_, awake_, 0.0, found_);
    for (const LimbContact& c : found_) {
      if (c.separation <= 0) contacts_.push_back({c.point, c.normal, -c.separation});
    }
  }
  const std::size_t limbs = model.bodies.size();
  for (std::size_t i = 0; i < limbs && model.ground; ++i) {
    for (const Eigen::Vector3d& end : {segments_[i].head, segments_[i].tail}) {
      const double depth = model.ground->height + segments_[i].radius - end.z();
      if (depth >= 0) contacts_.push_back({{end.x(), end.y(), model.ground->height}, Eigen::Vector3d::UnitZ(), depth});
    }
  }
  for (std::size_t k = 0; k < model.balls.size() && limbs + k < segments_.size(); ++k) {
    const Eigen::Vector3d centre = segments_[limbs + k].head;
    for (std::size_t i = 0; i < limbs; ++i) {
      const SegmentClosestPoints closest = closest_points_between_segments(centre, centre, segments_[i].head, segments_[i].tail);
      const double depth = model.balls[k].radius + segments_[i].radius - closest.distance;
      if (depth < 0 || closest.distance == 0) continue;
      const Eigen::Vector3d normal = (centre - closest.on_second) / closest.distance;
      contacts_.push_back({closest.on_second + segments_[i].radius * normal, normal, depth});
    }
  }
  return contacts_;
}

void SceneDrawer::draw(const ViewState& view, DrawList& list) {
  list.clear();
  const World& world = view.world();
  const Model& model = world.model();
  if (model.ground) {
    // The floor follows the camera, in whole tiles, so its pattern does not swim.
    const Eigen::Vector2d centre = view.camera.target.head<2>().array().round();
    list.floor = Floor{float(model.ground->height), centre.cast<float>(), float(std::max(20.0, 4 * view.camera.distance)), 0.5f};
  }
  draw_bodies(view, list);
  draw_level(model, list);
  draw_overlays(view, *this, list);
}

}  // namespace limber::viewer
