#include "limber/kernel/verlet/frames.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/checks.hpp"

namespace limber::frames {
namespace {

using checks::format_vector;

// A frame particle carries this fraction of its limb's mass (two of them: a quarter).
constexpr double kFrameMassFraction = 0.125;
// δ is at least this fraction of the limb's length, so a thin limb's frame is not degenerate
// (a zero-radius limb has no roll inertia in the Model; its frame gives it m·(0.1 L)²/4).
constexpr double kSmallestSpacing = 0.1;

[[noreturn]] void refuse_joint(const Model& model, std::size_t k, const std::string& problem) {
  throw ModelError("joints[" + std::to_string(k) + "] '" + model.joints[k].name + "': the particle (Verlet) method " + problem);
}

// The part of a body-frame anchor off the limb's axis.
Vector3 radial(const Vector3& anchor) { return {anchor.x(), anchor.y(), 0}; }

// The rows a joint needs beyond its point: does side A (inboard) or B need a frame?
struct FrameNeeds {
  bool inboard = false, outboard = false;
};
FrameNeeds frame_needs(const Joint& joint) {
  switch (joint.type) {
    case JointType::revolute:
    case JointType::universal:
    case JointType::fixed: return {true, true};
    default: break;
  }
  const bool roll = joint.limits.twist || joint.drive || joint.friction > 0;
  return {roll || joint.limits.swing.has_value(), roll};
}

Eigen::Matrix3d particle_frame(const Body& body, const Vector3& direction) {
  const Vector3 u = body.axis.normalized();
  const Vector3 v = (body.orientation() * direction).normalized();
  Eigen::Matrix3d frame;
  frame.col(0) = v, frame.col(1) = u.cross(v), frame.col(2) = u;
  return frame;
}

// A body's anchors off its axis, in joint order, must lie in the plane of the first: `normal`,
// set from it (⟂ the axis, body frame).
struct AnchorPlane {
  std::optional<Vector3> normal;
  // Whether `anchor` (body frame) fits, setting the plane from it when it is the first.
  bool fits(const Body& body, const Vector3& anchor) {
    const Vector3 r = radial(anchor);
    if (anchor_end(body, anchor) || r.norm() <= 1e-9 * std::max(1.0, axis_length(body))) return true;
    if (!normal) {
      normal = Vector3::UnitZ().cross(r).normalized();
      return true;
    }
    return std::abs(normal->dot(r)) <= 1e-9 * std::max(1.0, r.norm());
  }
};

// Each fixed joint's anchors at its inboard limb's centre (the world's point for a weld to it).
bool weld_at_inboard_centres(Model& model) {
  bool moved = false;
  for (Joint& joint : model.joints) {
    if (joint.type != JointType::fixed || joint.inboard == kWorld || joint.inboard_anchor.isZero(0)) continue;
    const Body& inboard = model.bodies[static_cast<std::size_t>(joint.inboard)];
    const Body& outboard = model.bodies[static_cast<std::size_t>(joint.outboard)];
    joint.inboard_anchor.setZero();
    joint.outboard_anchor = outboard.orientation().conjugate() * (inboard.position - outboard.position);
    moved = true;
  }
  return moved;
}

}  // namespace

bool anchors_to_place(const Model& model) {
  std::vector<AnchorPlane> planes(model.bodies.size());
  for (const Joint& joint : model.joints) {
    if (joint.inboard != kWorld && !planes[static_cast<std::size_t>(joint.inboard)].fits(model.bodies[static_cast<std::size_t>(joint.inboard)], joint.inboard_anchor)) return true;
    if (!planes[static_cast<std::size_t>(joint.outboard)].fits(model.bodies[static_cast<std::size_t>(joint.outboard)], joint.outboard_anchor)) return true;
  }
  return false;
}

bool place_anchors(Model& model) {
  bool moved = weld_at_inboard_centres(model);
  std::vector<AnchorPlane> planes(model.bodies.size());
  const auto body = [&](int b) -> const Body& { return model.bodies[static_cast<std::size_t>(b)]; };
  const auto anchor_of = [](const Joint& joint, int b) { return b == joint.inboard ? joint.inboard_anchor : joint.outboard_anchor; };
  for (Joint& joint : model.joints) {
    const int inboard = joint.inboard, outboard = joint.outboard;
    AnchorPlane in = inboard == kWorld ? AnchorPlane{} : planes[static_cast<std::size_t>(inboard)];
    AnchorPlane out = planes[static_cast<std::size_t>(outboard)];
    const bool inboard_fits = inboard == kWorld || in.fits(body(inboard), joint.inboard_anchor);
    const bool outboard_fits = out.fits(body(outboard), joint.outboard_anchor);
    if (inboard_fits && outboard_fits) {
      if (inboard != kWorld) planes[static_cast<std::size_t>(inboard)] = in;
      planes[static_cast<std::size_t>(outboard)] = out;
      continue;
    }
    if (joint.type != JointType::revolute || (!inboard_fits && !outboard_fits)) continue;  // plan() refuses
    // Slide the anchor along the hinge by t into the plane of the side that does not fit; the
    // other side takes it if it still fits there.
    const int side = inboard_fits ? outboard : inboard, other = inboard_fits ? inboard : outboard;
    const Body& b = body(side);
    const Vector3 local = anchor_of(joint, side), normal = *planes[static_cast<std::size_t>(side)].normal;
    const double along = normal.dot(b.orientation().conjugate() * joint.axis);
    if (std::abs(along) < 1e-6) continue;  // the hinge runs in the plane: plan() refuses
    const Vector3 world = b.to_world(local) - (normal.dot(radial(local)) / along) * joint.axis;
    Joint slid = joint;
    slid.outboard_anchor = body(outboard).orientation().conjugate() * (world - body(outboard).position);
    slid.inboard_anchor = inboard == kWorld ? world : Vector3(body(inboard).orientation().conjugate() * (world - body(inboard).position));
    AnchorPlane other_plane = other == kWorld ? AnchorPlane{} : planes[static_cast<std::size_t>(other)];
    AnchorPlane side_plane = planes[static_cast<std::size_t>(side)];
    if (!side_plane.fits(b, anchor_of(slid, side))) continue;
    if (other != kWorld && !other_plane.fits(body(other), anchor_of(slid, other))) continue;
    joint = slid, moved = true;
    planes[static_cast<std::size_t>(side)] = side_plane;
    if (other != kWorld) planes[static_cast<std::size_t>(other)] = other_plane;
  }
  return moved;
}

double axis_length(const Body& body) {
  return body.shape.length > 0 ? body.shape.length : std::sqrt(2.0) * body.shape.radius;
}

std::optional<End> anchor_end(const Body& body, const Vector3& anchor) {
  const double half = 0.5 * axis_length(body);
  const double tolerance = 1e-9 * std::max(1.0, axis_length(body));
  if ((anchor - Vector3(0, 0, half)).norm() <= tolerance) return End::head;
  if ((anchor - Vector3(0, 0, -half)).norm() <= tolerance) return End::tail;
  return std::nullopt;
}

Plan plan(const Model& model, bool shared_particles, std::vector<std::array<double, 3>>& limb_masses) {
  const std::size_t body_count = model.bodies.size(), joint_count = model.joints.size();
  Plan result;
  result.framed.assign(body_count, false);
  result.direction.assign(body_count, Vector3::UnitX());
  result.spacing.assign(body_count, 0.0);
  result.frame_mass.assign(body_count, 0.0);
  result.point_row.assign(joint_count, false);
  std::vector<bool> has_radial(body_count, false);
  std::vector<std::size_t> radial_joint(body_count, 0);
  for (std::size_t k = 0; k < joint_count; ++k) {
    const Joint& joint = model.joints[k];
    if (joint.type == JointType::prismatic) {
      refuse_joint(model, k, "does not support prismatic joints (lagrange and featherstone do)");
    }
    if (joint.type == JointType::universal && joint.friction > 0) {
      refuse_joint(model, k, "does not apply friction to universal joints (lagrange does)");
    }
    const FrameNeeds needs = frame_needs(joint);
    const auto side = [&](int body_index, const Vector3& anchor, bool needs_frame) {
      if (body_index == kWorld) return true;
      const auto b = static_cast<std::size_t>(body_index);
      if (needs_frame) result.framed[b] = true;
      const bool at_end = anchor_end(model.bodies[b], anchor).has_value();
      const Vector3 off_axis = radial(anchor);
      if (!at_end && off_axis.norm() > 1e-9 * std::max(1.0, axis_length(model.bodies[b]))) {
        result.framed[b] = true;
        if (!has_radial[b]) {
          has_radial[b] = true, radial_joint[b] = k;
          result.direction[b] = off_axis.normalized();
        } else if (off_axis.normalized().cross(result.direction[b]).norm() > 1e-9) {
          refuse_joint(model, k,
                       "places anchors off a limb's axis in one plane through it (its frame's): body '" + model.bodies[b].name +
                           "' has an anchor " + format_vector(anchor) + " out of the plane of joints[" +
                           std::to_string(radial_joint[b]) + "]'s; move it into that plane or onto the axis");
        }
      }
      return at_end;
    };
    const bool inboard_at_end = side(joint.inboard, joint.inboard_anchor, needs.inboard);
    const bool outboard_at_end = side(joint.outboard, joint.outboard_anchor, needs.outboard);
    result.point_row[k] = !inboard_at_end || !outboard_at_end;
    const bool rows = result.point_row[k] || joint.type != JointType::spherical || has_joint_controls(joint);
    if (rows && shared_particles) {
      refuse_joint(model, k, "holds anchors off the limb ends, hinges, limits, friction and drives with joints "
                             "\"zero_length_constraint\" only (settings.verlet.joints), not \"shared_particle\"");
    }
    result.any_rows = result.any_rows || rows;
  }
  for (std::size_t b = 0; b < body_count; ++b) {
    if (!result.framed[b]) continue;
    result.any_frames = result.any_rows = true;
    const Body& body = model.bodies[b];
    double& head = limb_masses[b][0];
    double& centre = limb_masses[b][1];
    double& tail = limb_masses[b][2];
    const double m = kFrameMassFraction * body.mass;
    if (centre > 2.5 * m) {
      centre -= 2 * m;
    } else if (head > 1.5 * m && tail > 1.5 * m) {
      head -= m, tail -= m;
    } else {
      throw ModelError("bodies[" + std::to_string(b) + "] '" + body.name + "': the particle (Verlet) method gives this limb a "
                       "frame (two particles of 1/8 of its mass each, taken from its ends) but its ends carry too little mass");
    }
    result.frame_mass[b] = m;
    const double axial_inertia = body_mass_properties(body).inertia(2, 2);
    result.spacing[b] = std::max(std::sqrt(axial_inertia / (2 * m)), kSmallestSpacing * axis_length(body));
  }
  return result;
}

namespace {

struct SideInfo {
  JointSide kind = JointSide::world;
  LimbParticles particles{};
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  ///< particle frame (v, w, u) → world, at rest
  Eigen::Vector3d to_side(const Eigen::Vector3d& world) const { return frame.transpose() * world; }
};

void put(std::array<double, kJointRowDirections>& direction, int first, const Eigen::Vector3d& value) {
  for (int i = 0; i < 3; ++i) direction[static_cast<std::size_t>(first + i)] = value[i];
}

}  // namespace

JointRowSet build_rows(const Model& model, const Plan& plan, const std::function<LimbParticles(std::size_t)>& limb_particles,
                       const std::function<std::uint32_t(std::size_t)>& pin_particle,
                       const std::function<std::uint32_t(std::size_t)>& island_of_body, std::uint32_t null_particle) {
  JointRowSet set;
  const std::size_t body_count = model.bodies.size();
  set.frame_plus.assign(body_count, null_particle), set.frame_minus.assign(body_count, null_particle);
  set.frame_to_body.assign(body_count, Eigen::Quaterniond::Identity());
  set.joint_rows.assign(model.joints.size(), {0u, 0u});
  const auto blank = [&](JointRowKind kind, std::uint32_t island) {
    JointRow row;
    row.kind = kind, row.island = island;
    row.particle.fill(null_particle);
    return row;
  };
  // Frames: F⁺ + F⁻ − head − tail = 0 (the distance constraints head–F⁺, tail–F⁺ are compile's).
  for (std::size_t b = 0; b < body_count; ++b) {
    if (!plan.framed[b]) continue;
    const LimbParticles p = limb_particles(b);
    set.frame_plus[b] = p[2], set.frame_minus[b] = p[3];
    const Eigen::Quaterniond frame(particle_frame(model.bodies[b], plan.direction[b]));
    set.frame_to_body[b] = frame.conjugate() * model.bodies[b].orientation();
    JointRow row = blank(JointRowKind::point, island_of_body(b));
    row.particle[0] = p[2], row.particle[1] = p[3], row.particle[2] = p[0], row.particle[3] = p[1];
    row.direction[0] = row.direction[1] = 1, row.direction[2] = row.direction[3] = -1;
    set.rows.push_back(row);
  }
  const auto side_of = [&](int body_index) {
    SideInfo side;
    side.particles.fill(null_particle);
    if (body_index == kWorld) return side;
    const auto b = static_cast<std::size_t>(body_index);
    side.particles = limb_particles(b);
    side.kind = plan.framed[b] ? JointSide::framed : JointSide::stick;
    side.frame = particle_frame(model.bodies[b], plan.direction[b]);
    return side;
  };
  // The anchor as affine coefficients of head, tail, F⁺, F⁻ (the frame's plane through the axis).
  const auto anchor_coefficients = [&](std::size_t b, const Vector3& anchor) {
    const Body& body = model.bodies[b];
    const double along = anchor.z() / axis_length(body);
    std::array<double, 4> c{0.5 + along, 0.5 - along, 0, 0};
    if (plan.framed[b]) {
      const double off = radial(anchor).dot(plan.direction[b]) / (2 * plan.spacing[b]);
      c[2] = off, c[3] = -off;
    }
    return c;
  };
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Joint& joint = model.joints[k];
    const auto first = static_cast<std::uint32_t>(set.rows.size());
    const SideInfo a = side_of(joint.inboard), b = side_of(joint.outboard);
    const std::uint32_t island = island_of_body(static_cast<std::size_t>(joint.outboard));
    const auto row_for = [&](JointRowKind kind) {
      JointRow row = blank(kind, island);
      row.side_a = a.kind, row.side_b = b.kind, row.joint = static_cast<std::int32_t>(k);
      for (std::size_t i = 0; i < kJointRowSideParticles; ++i) {
        row.particle[i] = a.particles[i], row.particle[kJointRowSideParticles + i] = b.particles[i];
      }
      return row;
    };
    if (plan.point_row[k]) {
      JointRow row = blank(JointRowKind::point, island);
      row.joint = static_cast<std::int32_t>(k);
      if (joint.inboard == kWorld) {
        row.particle[0] = pin_particle(k), row.direction[0] = 1;
      } else {
        const auto c = anchor_coefficients(static_cast<std::size_t>(joint.inboard), joint.inboard_anchor);
        for (std::size_t i = 0; i < 4; ++i) row.particle[i] = a.particles[i], row.direction[i] = c[i];
      }
      const auto c = anchor_coefficients(static_cast<std::size_t>(joint.outboard), joint.outboard_anchor);
      for (std::size_t i = 0; i < 4; ++i) row.particle[5 + i] = b.particles[i], row.direction[5 + i] = -c[i];
      const double outboard_length = axis_length(model.bodies[static_cast<std::size_t>(joint.outboard)]);
      row.reference = joint.inboard == kWorld ? outboard_length
                                              : 0.5 * (outboard_length + axis_length(model.bodies[static_cast<std::size_t>(joint.inboard)]));
      set.rows.push_back(row);
    }
    const Body& outboard = model.bodies[static_cast<std::size_t>(joint.outboard)];
    // A unit vector ⟂ `axis`: the outboard frame's v at rest made orthogonal (for hinge references).
    const auto perpendicular_to = [&](const Vector3& axis) {
      Vector3 r = b.frame.col(0) - b.frame.col(0).dot(axis) * axis;
      if (r.norm() < 1e-6) r = b.frame.col(1) - b.frame.col(1).dot(axis) * axis;
      return Vector3(r.normalized());
    };
    const Eigen::Matrix3d rest_basis = b.frame;  // B's (v, w, u) at rest, world
    switch (joint.type) {
      case JointType::revolute: {
        JointRow row = row_for(JointRowKind::align);
        put(row.direction, 0, a.to_side(joint.axis)), put(row.direction, 3, b.to_side(joint.axis));
        set.rows.push_back(row);
        const Vector3 reference = perpendicular_to(joint.axis);
        JointRow angle = row_for(JointRowKind::hinge);
        put(angle.direction, 0, a.to_side(joint.axis)), put(angle.direction, 3, a.to_side(reference));
        put(angle.direction, 6, b.to_side(reference));
        if (const auto& range = joint.limits.range) {
          JointRow limit = angle;
          limit.lower = range->min, limit.upper = range->max;
          set.rows.push_back(limit);
        }
        if (const auto& drive = joint.drive) {
          JointRow motor = angle;
          motor.drive = true;
          set_drive_row(motor, *drive);
          set.rows.push_back(motor);
        }
        if (joint.friction > 0) {
          JointRow friction = angle;
          friction.blend = 1, friction.friction = joint.friction;
          set.rows.push_back(friction);
        }
        break;
      }
      case JointType::universal: {
        JointRow row = row_for(JointRowKind::perpendicular);
        put(row.direction, 0, a.to_side(joint.axis)), put(row.direction, 3, b.to_side(joint.second_axis));
        set.rows.push_back(row);
        break;
      }
      case JointType::fixed: {
        JointRow row = row_for(JointRowKind::orientation);
        for (int i = 0; i < 3; ++i) put(row.direction, 3 * i, a.to_side(rest_basis.col(i)));
        set.rows.push_back(row);
        break;
      }
      case JointType::spherical: {
        const Vector3 cone = joint.limits.swing_axis.value_or(outboard.axis).normalized();
        if (joint.limits.swing) {
          JointRow row = row_for(JointRowKind::swing);
          put(row.direction, 0, a.to_side(cone));
          row.upper = *joint.limits.swing;
          set.rows.push_back(row);
        }
        if (const auto& twist = joint.limits.twist) {
          // About the cone axis (joint_coordinates.hpp): A's reference is B's v at rest turned by
          // the shortest arc from B's axis onto the cone's, so carried back it meets v at rest.
          JointRow row = row_for(JointRowKind::twist);
          const Vector3 reference = Eigen::Quaterniond::FromTwoVectors(rest_basis.col(2), cone) * rest_basis.col(0);
          put(row.direction, 0, a.to_side(cone)), put(row.direction, 3, a.to_side(reference));
          put(row.direction, 6, Vector3::UnitX());
          row.lower = twist->min, row.upper = twist->max;
          set.rows.push_back(row);
        }
        if (const auto& drive = joint.drive) {
          JointRow row = row_for(JointRowKind::orientation);
          row.drive = true;
          row.inboard_frame = a.frame;
          row.rest_basis = a.frame.transpose() * rest_basis;
          set_drive_row(row, *drive);
          set.rows.push_back(row);
        }
        if (joint.friction > 0) {
          JointRow row = row_for(JointRowKind::orientation);
          row.blend = 1, row.friction = joint.friction;
          set.rows.push_back(row);
        }
        break;
      }
      case JointType::prismatic:  // refused by plan(), as serial is
      case JointType::serial: break;
    }
    set.joint_rows[k] = {first, static_cast<std::uint32_t>(set.rows.size())};
  }
  return set;
}

}  // namespace limber::frames
