#include "limber/kernel/verlet/particle_plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/checks.hpp"
#include "limber/layouts/graph/disjoint_sets.hpp"

namespace limber::particle_plan {
namespace {

using frames::End;

// Which axis end point a joint anchor is (joints held by a point row, off the ends, take the
// head's slot: they are never merged, since shared particles refuse them).
End anchor_end(const Model& model, std::size_t joint_index, bool inboard) {
  const Joint& joint = model.joints[joint_index];
  const Body& body = model.bodies[inboard ? joint.inboard : joint.outboard];
  return frames::anchor_end(body, inboard ? joint.inboard_anchor : joint.outboard_anchor).value_or(End::head);
}

// LimbMasses::inertia (thesis 4.1: placing particle masses so that a link's mass, centre of mass
// and inertia are reproduced). Masses at z = −h, 0, +h on the axis (h = L/2) solve
//   m_tail + m_centre + m_head = m,   h·(m_head − m_tail) = m·c_z,   h²·(m_head + m_tail) = S,
// with S = I_t + m·c_z² the second moment about a transverse axis through the limb's centre and
// I_t the transverse inertia about the centre of mass (body_mass_properties). Points on the axis
// have the same inertia about every transverse axis and none about the axis itself, so I_t is
// the mean of I_xx and I_yy (exact for cylinders, capsules and lumps on the axis; for a limb
// that is not axially symmetric the difference is lost), and the spin about the axis is not
// represented — as with two particles. Throws ModelError, naming the body, for what three
// positive masses on the axis cannot represent: a centre of mass off the axis, or S outside
// (m·|c_z|·h, m·h²) (a disc-like cylinder, radius²/4 ≥ L²/6; a lump beyond an end; all the mass
// at one point).
LimbParticleMasses inertia_particle_masses(const Model& model, std::size_t index) {
  using checks::format_number;
  const Body& body = model.bodies[index];
  std::ostringstream message;
  message << "bodies[" << index << "] '" << body.name << "': limb_masses \"inertia\" needs ";
  const MassProperties properties = body_mass_properties(body);
  const Vector3& centre_of_mass = properties.centre_of_mass;
  if (centre_of_mass.head<2>().norm() > 1e-9 * frames::axis_length(body)) {
    message << "the centre of mass on the limb's axis (body-frame x = y = 0), got [" << format_number(centre_of_mass.x())
            << ", " << format_number(centre_of_mass.y()) << ", " << format_number(centre_of_mass.z())
            << "] m; move the point masses onto the axis or use limb_masses \"ends\"";
    throw ModelError(message.str());
  }
  const double mass = body.mass, h = 0.5 * frames::axis_length(body), c = centre_of_mass.z();
  const double transverse_inertia = 0.5 * (properties.inertia(0, 0) + properties.inertia(1, 1));
  const double second_moment = transverse_inertia + mass * c * c;
  LimbParticleMasses masses;
  masses.head = 0.5 * (second_moment / (h * h) + mass * c / h);
  masses.tail = 0.5 * (second_moment / (h * h) - mass * c / h);
  masses.centre = mass - masses.head - masses.tail;
  const double smallest = 1e-12 * mass;  // a zero lost to rounding is still zero (w = 0 would pin it)
  if (!(masses.head > smallest && masses.tail > smallest && masses.centre > smallest)) {
    message << "its transverse second moment about its centre in (m |c_z| L/2, m L^2/4) = ("
            << format_number(mass * std::abs(c) * h) << ", " << format_number(mass * h * h)
            << ") kg m^2 for positive tail, centre and head masses, got " << format_number(second_moment)
            << " kg m^2 (masses " << format_number(masses.tail) << ", " << format_number(masses.centre) << ", "
            << format_number(masses.head) << " kg: "
            << (masses.centre > smallest ? "its mass is too concentrated" : "it is too wide for its length")
            << "); use limb_masses \"ends\"";
    throw ModelError(message.str());
  }
  return masses;
}

// LimbMasses::lumps: each point mass m_k at z_k on the axis goes to the head and the tail by the
// lever rule, m_head += m_k·(z_k + h)/L and m_tail += m_k·(h − z_k)/L (h = L/2): the pair keeps
// the lump's mass and centre, and a lump at an end goes wholly to that end's particle, so a body
// of lumps at its ends is represented exactly. Throws ModelError, naming the body, for a body
// without point masses and for a lump off the axis or beyond an end, which two particles cannot
// carry. A lump's own radius (a solid sphere's inertia, 2/5·m·r²) is not represented.
LimbParticleMasses lump_particle_masses(const Model& model, std::size_t index) {
  using checks::format_number;
  const Body& body = model.bodies[index];
  const auto refuse = [&](std::size_t lump, const char* problem) {
    std::ostringstream message;
    message << "bodies[" << index << "] '" << body.name << "': limb_masses \"lumps\" " << problem;
    if (lump < body.point_masses.size()) {
      const Vector3& at = body.point_masses[lump].position;
      message << "; point_masses[" << lump << "] at [" << format_number(at.x()) << ", " << format_number(at.y()) << ", "
              << format_number(at.z()) << "] m is not";
    }
    throw ModelError(message.str());
  };
  if (body.point_masses.empty()) refuse(0, "needs point_masses on every body; this one has a uniform density");
  const double length = frames::axis_length(body), half = 0.5 * length, tolerance = 1e-9 * length;
  LimbParticleMasses masses;
  for (std::size_t k = 0; k < body.point_masses.size(); ++k) {
    const PointMass& lump = body.point_masses[k];
    if (lump.position.head<2>().norm() > tolerance) refuse(k, "needs every point mass on the limb's axis (x = y = 0)");
    if (std::abs(lump.position.z()) > half + tolerance) refuse(k, "needs every point mass between the limb's ends (|z| <= length/2)");
    const double z = std::clamp(lump.position.z(), -half, half);
    masses.head += lump.mass * (z + half) / length;
    masses.tail += lump.mass * (half - z) / length;
  }
  return masses;
}

}  // namespace

std::uint32_t checked_index(std::size_t value) {
  if (value >= std::numeric_limits<std::uint32_t>::max()) {
    throw ModelError("model: too many particles or constraints for 32-bit indices");
  }
  return static_cast<std::uint32_t>(value);
}

void plan_limb_masses(const Model& model, const VerletOptions& options, Plan& plan) {
  const std::size_t body_count = model.bodies.size();
  plan.shared = options.verlet.joints == ParticleJoints::shared_particle;
  plan.centres = options.verlet.limb_masses == LimbMasses::inertia;
  std::vector<LimbParticleMasses>& limb_masses = plan.limb_masses;
  limb_masses.resize(body_count);
  for (std::size_t b = 0; b < body_count; ++b) {
    const double half = 0.5 * model.bodies[b].mass;
    switch (options.verlet.limb_masses) {
      case LimbMasses::ends: limb_masses[b] = LimbParticleMasses{half, 0.0, half}; break;
      case LimbMasses::inertia: limb_masses[b] = inertia_particle_masses(model, b); break;
      case LimbMasses::lumps: limb_masses[b] = lump_particle_masses(model, b); break;
    }
  }
  // Frames and joint rows (frames.hpp): a framed limb gives its frame particles their mass.
  std::vector<std::array<double, 3>> mass_triples(body_count);
  for (std::size_t b = 0; b < body_count; ++b) mass_triples[b] = {limb_masses[b].head, limb_masses[b].centre, limb_masses[b].tail};
  plan.frames = frames::plan(model, plan.shared, mass_triples);
  for (std::size_t b = 0; b < body_count; ++b) limb_masses[b] = {mass_triples[b][2], mass_triples[b][1], mass_triples[b][0]};
}

void plan_slots(const Model& model, Plan& plan) {
  const std::size_t joint_count = model.joints.size();
  plan.frame_slot_offset = plan.centres ? 3 : 2;
  plan.slots_per_body = plan.frame_slot_offset + (plan.frames.any_frames ? 2 : 0);
  plan.pin_slot_base = plan.slots_per_body * model.bodies.size();
  plan.joint_inboard_slot.assign(joint_count, 0);
  plan.joint_outboard_slot.assign(joint_count, 0);
  plan.pin_slot_of_joint.assign(joint_count, 0);
  plan.slot_count = plan.pin_slot_base;
  for (std::size_t k = 0; k < joint_count; ++k) {
    const Joint& joint = model.joints[k];
    const End outboard_end = anchor_end(model, k, false);
    plan.joint_outboard_slot[k] = outboard_end == End::tail ? plan.tail_slot(joint.outboard) : plan.head_slot(joint.outboard);
    if (joint.inboard == kWorld) {
      plan.pin_slot_of_joint[k] = checked_index(plan.slot_count++);
      plan.joint_inboard_slot[k] = plan.pin_slot_of_joint[k];
    } else {
      plan.joint_inboard_slot[k] = anchor_end(model, k, true) == End::tail ? plan.tail_slot(joint.inboard) : plan.head_slot(joint.inboard);
    }
  }
}

void place_slots(const Model& model, Plan& plan) {
  const std::size_t slot_count = plan.slot_count;
  const frames::Plan& frame_plan = plan.frames;
  std::vector<Vector3>& slot_position = plan.slot_position;
  std::vector<Vector3>& slot_velocity = plan.slot_velocity;
  std::vector<double>& slot_mass = plan.slot_mass;
  slot_position.assign(slot_count, Vector3::Zero());
  slot_velocity.assign(slot_count, Vector3::Zero());
  slot_mass.assign(slot_count, 0.0);
  plan.slot_pinned.assign(slot_count, false);
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    const double half = 0.5 * frames::axis_length(body);  // Body::head() and tail(), of a sphere too
    const Vector3 head_local(0, 0, half);
    slot_position[plan.head_slot(b)] = body.position + half * body.axis;
    slot_position[plan.tail_slot(b)] = body.position - half * body.axis;
    slot_velocity[plan.head_slot(b)] = body.velocity_at(head_local);
    slot_velocity[plan.tail_slot(b)] = body.velocity_at(-head_local);
    slot_mass[plan.head_slot(b)] = plan.limb_masses[b].head;
    slot_mass[plan.tail_slot(b)] = plan.limb_masses[b].tail;
    if (plan.centres) {
      slot_position[plan.centre_slot(b)] = body.position;
      slot_velocity[plan.centre_slot(b)] = body.linear_velocity;
      slot_mass[plan.centre_slot(b)] = plan.limb_masses[b].centre;
    }
    if (frame_plan.framed[b]) {
      for (int side = 0; side < 2; ++side) {
        const Vector3 local = (side == 0 ? 1.0 : -1.0) * frame_plan.spacing[b] * frame_plan.direction[b];
        slot_position[plan.frame_slot(b, side)] = body.to_world(local);
        slot_velocity[plan.frame_slot(b, side)] = body.velocity_at(local);
        slot_mass[plan.frame_slot(b, side)] = frame_plan.frame_mass[b];
      }
    }
  }
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    if (model.joints[k].inboard != kWorld) continue;
    slot_position[plan.pin_slot_of_joint[k]] = model.joints[k].inboard_anchor;
    plan.slot_pinned[plan.pin_slot_of_joint[k]] = true;
  }
}

void plan_islands(const Model& model, Plan& plan) {
  const std::size_t body_count = model.bodies.size();
  plan.islands = body_islands(model);
  const BodyIslands& islands = plan.islands;
  using Neighbour = Plan::Neighbour;
  std::vector<std::pair<std::uint32_t, Neighbour>> neighbour_pairs;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> world_joint_pairs;
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Joint& joint = model.joints[k];
    const auto j = static_cast<std::uint32_t>(k);
    const auto outboard = static_cast<std::uint32_t>(joint.outboard);
    if (joint.inboard == kWorld) {
      world_joint_pairs.emplace_back(outboard, j);
      continue;
    }
    const auto inboard = static_cast<std::uint32_t>(joint.inboard);
    neighbour_pairs.push_back({inboard, {j, outboard}});
    neighbour_pairs.push_back({outboard, {j, inboard}});
  }
  plan.neighbours = group_by_row(body_count, neighbour_pairs);
  plan.world_joints = group_by_row(body_count, world_joint_pairs);

  // Each island starts from its first body held by the world, else its first body.
  std::vector<std::uint32_t> island_root(islands.count);
  for (std::size_t b = body_count; b-- > 0;) {  // descending, so the lowest (held) body wins
    island_root[islands.island_of_body[b]] = static_cast<std::uint32_t>(b);
  }
  for (std::size_t b = body_count; b-- > 0;) {
    if (!plan.world_joints.row(b).empty()) island_root[islands.island_of_body[b]] = static_cast<std::uint32_t>(b);
  }

  // Breadth-first order of each island's bodies from its root; body_order doubles as the queue.
  std::vector<std::uint32_t>& body_order = plan.body_order;
  body_order.reserve(body_count);
  plan.tree_joint.assign(body_count, -1);
  std::vector<bool> visited(body_count, false);
  for (std::size_t island = 0; island < islands.count; ++island) {
    plan.island_begin.push_back(static_cast<std::uint32_t>(body_order.size()));
    const std::uint32_t root = island_root[island];
    body_order.push_back(root);
    visited[root] = true;
    for (std::size_t next = plan.island_begin.back(); next < body_order.size(); ++next) {
      for (const auto& [joint, other] : plan.neighbours.row(body_order[next])) {
        if (visited[other]) continue;
        visited[other] = true;
        plan.tree_joint[other] = joint;
        body_order.push_back(other);
      }
    }
  }
  plan.island_begin.push_back(static_cast<std::uint32_t>(body_order.size()));
}

void number_particles(const Model& model, Plan& plan) {
  // Merge slots joined by shared-particle joints (a world joint pins the body's own end).
  DisjointSets merged(plan.slot_count);
  if (plan.shared) {
    for (std::size_t k = 0; k < model.joints.size(); ++k) merged.unite(plan.joint_inboard_slot[k], plan.joint_outboard_slot[k]);
  }
  std::vector<std::uint32_t> particle_of_root(plan.slot_count, Plan::kUnassigned);
  const auto assign = [&](std::uint32_t slot) {
    const std::uint32_t root = merged.find(slot);
    if (particle_of_root[root] == Plan::kUnassigned) {
      particle_of_root[root] = checked_index(plan.first_slot_of_particle.size());
      plan.first_slot_of_particle.push_back(slot);
    }
  };
  for (std::size_t island = 0; island < plan.island_count(); ++island) {
    for (std::uint32_t b : plan.island_bodies(island)) {
      if (!plan.shared) for (std::uint32_t k : plan.world_joints.row(b)) assign(plan.pin_slot_of_joint[k]);
      assign(plan.head_slot(b));
      if (plan.centres) assign(plan.centre_slot(b));
      assign(plan.tail_slot(b));
      if (plan.frames.framed[b]) assign(plan.frame_slot(b, 0)), assign(plan.frame_slot(b, 1));
    }
    plan.island_particle_end.push_back(checked_index(plan.first_slot_of_particle.size()));
  }
  plan.particle_of_slot.resize(plan.slot_count);
  for (std::uint32_t slot = 0; slot < plan.slot_count; ++slot) plan.particle_of_slot[slot] = particle_of_root[merged.find(slot)];
}

}  // namespace limber::particle_plan
