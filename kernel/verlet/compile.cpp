#include "limber/kernel/verlet/compile.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"
#include "limber/kernel/verlet/bodies.hpp"
#include "limber/kernel/verlet/frames.hpp"
#include "limber/layouts/graph/compressed_rows.hpp"
#include "limber/layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

using frames::End;

// Which axis end point a joint anchor is (joints held by a point row, off the ends, take the
// head's slot: they are never merged, since shared particles refuse them).
End anchor_end(const Model& model, std::size_t joint_index, bool inboard) {
  const Joint& joint = model.joints[joint_index];
  const Body& body = model.bodies[inboard ? joint.inboard : joint.outboard];
  return frames::anchor_end(body, inboard ? joint.inboard_anchor : joint.outboard_anchor).value_or(End::head);
}

// A limb's own mass at each of its particles, kg.
struct LimbParticleMasses {
  double tail = 0, centre = 0, head = 0;
};

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
  if (centre_of_mass.head<2>().norm() > 1e-9 * body.shape.length) {
    message << "the centre of mass on the limb's axis (body-frame x = y = 0), got [" << format_number(centre_of_mass.x())
            << ", " << format_number(centre_of_mass.y()) << ", " << format_number(centre_of_mass.z())
            << "] m; move the point masses onto the axis or use limb_masses \"ends\"";
    throw ModelError(message.str());
  }
  const double mass = body.mass, h = 0.5 * body.shape.length, c = centre_of_mass.z();
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
  const double half = 0.5 * body.shape.length, tolerance = 1e-9 * body.shape.length;
  LimbParticleMasses masses;
  for (std::size_t k = 0; k < body.point_masses.size(); ++k) {
    const PointMass& lump = body.point_masses[k];
    if (lump.position.head<2>().norm() > tolerance) refuse(k, "needs every point mass on the limb's axis (x = y = 0)");
    if (std::abs(lump.position.z()) > half + tolerance) refuse(k, "needs every point mass between the limb's ends (|z| <= length/2)");
    const double z = std::clamp(lump.position.z(), -half, half);
    masses.head += lump.mass * (z + half) / body.shape.length;
    masses.tail += lump.mass * (half - z) / body.shape.length;
  }
  return masses;
}

std::uint32_t checked_index(std::size_t value) {
  if (value >= std::numeric_limits<std::uint32_t>::max()) {
    throw ModelError("model: too many particles or constraints for 32-bit indices");
  }
  return static_cast<std::uint32_t>(value);
}

// Renumbers each island's particles in `options.ordering` (particle_ordering.hpp), moving
// every per-particle array and rewriting every particle index. Islands keep their ranges.
template <typename Scalar>
void renumber_particles(VerletState<Scalar>& state) {
  const ParticleOrder ordering = state.options.ordering;
  if (ordering == ParticleOrder::breadth_first) return;
  const std::size_t count = state.particles.size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> neighbour_pairs;
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
    neighbour_pairs.emplace_back(i, j), neighbour_pairs.emplace_back(j, i);
  }
  const CompressedRows<std::uint32_t> adjacency = group_by_row(count, neighbour_pairs);
  std::vector<std::uint32_t> new_index(count);
  for (const Island& island : state.islands) {
    const std::vector<std::uint32_t> order =
        ordering == ParticleOrder::shuffled       ? shuffled_order(island.particle_begin, island.particle_end)
        : ordering == ParticleOrder::depth_parity ? depth_parity_order(adjacency, island.particle_begin, island.particle_end)
                                                  : reverse_cuthill_mckee(adjacency, island.particle_begin, island.particle_end);
    for (std::size_t k = 0; k < order.size(); ++k) new_index[order[k]] = island.particle_begin + static_cast<std::uint32_t>(k);
  }
  ParticleBuffer<Scalar> particles;
  particles.resize(count);
  std::vector<double> particle_mass(count);
  std::vector<ParticleOrigin> origins(count);
  for (std::size_t p = 0; p < count; ++p) {
    const std::uint32_t q = new_index[p];
    particles.set_position(q, state.particles.position(p));
    particles.set_previous(q, state.particles.previous(p));
    particles.set_velocity(q, state.particles.velocity(p));
    particles.inverse_mass[q] = state.particles.inverse_mass[p];
    particle_mass[q] = state.particle_mass[p];
    origins[q] = state.particle_origins[p];
  }
  state.particles = std::move(particles);
  state.particle_mass = std::move(particle_mass);
  state.particle_origins = std::move(origins);
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    state.constraints.particle_i[c] = new_index[state.constraints.particle_i[c]];
    state.constraints.particle_j[c] = new_index[state.constraints.particle_j[c]];
  }
  for (auto* list : {&state.limbs.head, &state.limbs.tail, &state.limbs.centre}) {
    for (std::uint32_t& p : *list) p = p == kNoCentre ? p : new_index[p];
  }
  for (ContactFeature& feature : state.features) {
    feature.particle = new_index[feature.particle], feature.axis_partner = new_index[feature.axis_partner];
  }
  for (BallParticle& ball : state.balls) ball.particle = new_index[ball.particle];
  const std::uint32_t null_particle = state.particles.null_particle();
  const auto renumbered = [&](std::uint32_t p) { return p == null_particle ? p : new_index[p]; };
  for (JointRow& row : state.joint_rows.rows) {
    for (std::uint32_t& p : row.particle) p = renumbered(p);
  }
  for (auto* list : {&state.joint_rows.frame_plus, &state.joint_rows.frame_minus}) {
    for (std::uint32_t& p : *list) p = renumbered(p);
  }
}

}  // namespace

namespace {

// The collision world (limb_collisions.hpp) and its scratch at full size, when the scene has
// limbs that may touch or static geometry: a scene without pays nothing for it.
template <typename Scalar>
void prepare_limb_collisions(VerletState<Scalar>& state, const Model& model) {
  state.collisions = LimbCollisions(model);
  if (!state.collisions.active()) return;
  const std::size_t segments = model.bodies.size() + state.balls.size();
  state.limb_segments.reserve(segments);
  state.limb_awake.reserve(segments);
  state.limb_island_awake.assign(state.limbs.size(), 0);
  state.contact_rows.particle_colours.assign(state.particles.size() + 1, 0);
  // Room for a few contacts per limb (a pile's are about four): more grows the buffers once.
  const std::size_t rows = 8 * segments + 64;
  state.limb_contacts.reserve(rows);
  state.contact_rows.rows.reserve(rows);
  state.contact_rows.colour.reserve(rows);
  state.contact_rows.order.reserve(rows);
  state.contact_particles.reserve(state.contact_particles.capacity() + kContactRowParticles * rows);
  state.plan.contact_batches.reserve(rows + (kMaxContactColours + 1) * ContactRowBatches<Scalar>::kBlockLanes, kMaxContactColours);
}

}  // namespace

template <typename Scalar>
VerletState<Scalar> compile(const Model& model, const VerletOptions& options) {
  validate(model);
  validate(options.relaxation);
  validate(options.verlet);
  require_supported(model, Method::particles);
  require_joint_controls(model, {true, true, true}, "verlet");
  const std::size_t body_count = model.bodies.size();
  const std::size_t joint_count = model.joints.size();
  const bool shared = options.verlet.joints == ParticleJoints::shared_particle;
  const bool centres = options.verlet.limb_masses == LimbMasses::inertia;
  const bool rattle = options.relaxation.projection == ProjectionRule::rattle;
  const double dt = model.settings.time_step;

  VerletState<Scalar> state;
  state.options = options;
  state.settings = model.settings;
  state.gravity = model.settings.gravity.cast<Scalar>();
  state.previous_time_step = dt;

  // Each limb's mass at its particles: half at each end, or three masses that keep its inertia.
  std::vector<LimbParticleMasses> limb_masses(body_count);
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
  const frames::Plan frame_plan = frames::plan(model, shared, mass_triples);
  for (std::size_t b = 0; b < body_count; ++b) limb_masses[b] = {mass_triples[b][2], mass_triples[b][1], mass_triples[b][0]};

  // Slots: every place a particle may sit. Body b has its head at slot s·b, its tail at s·b + 1
  // and, with centre particles (s = 3; else s = 2), its centre at s·b + 2; each joint to the world
  // has a pin slot after them. Shared-particle joints merge slots into one particle.
  // Framed limbs' F⁺ and F⁻ follow at s·b + (2 or 3) and the next.
  const std::uint32_t frame_slot_offset = centres ? 3 : 2;
  const std::uint32_t slots_per_body = frame_slot_offset + (frame_plan.any_frames ? 2 : 0);
  const auto head_slot = [&](std::size_t b) { return checked_index(slots_per_body * b); };
  const auto tail_slot = [&](std::size_t b) { return checked_index(slots_per_body * b + 1); };
  const auto centre_slot = [&](std::size_t b) { return checked_index(slots_per_body * b + 2); };
  const auto frame_slot = [&](std::size_t b, int side) { return checked_index(slots_per_body * b + frame_slot_offset + side); };
  const std::size_t pin_slot_base = slots_per_body * body_count;
  std::vector<std::uint32_t> joint_inboard_slot(joint_count), joint_outboard_slot(joint_count);
  std::vector<std::uint32_t> pin_slot_of_joint(joint_count, 0);
  std::size_t slot_count = pin_slot_base;
  for (std::size_t k = 0; k < joint_count; ++k) {
    const Joint& joint = model.joints[k];
    const End outboard_end = anchor_end(model, k, false);
    joint_outboard_slot[k] = outboard_end == End::tail ? tail_slot(joint.outboard) : head_slot(joint.outboard);
    if (joint.inboard == kWorld) {
      pin_slot_of_joint[k] = checked_index(slot_count++);
      joint_inboard_slot[k] = pin_slot_of_joint[k];
    } else {
      joint_inboard_slot[k] = anchor_end(model, k, true) == End::tail ? tail_slot(joint.inboard) : head_slot(joint.inboard);
    }
  }

  // Slot positions, velocities, mass shares, pins.
  std::vector<Vector3> slot_position(slot_count), slot_velocity(slot_count, Vector3::Zero());
  std::vector<double> slot_mass(slot_count, 0.0);
  std::vector<bool> slot_pinned(slot_count, false);
  for (std::size_t b = 0; b < body_count; ++b) {
    const Body& body = model.bodies[b];
    const Vector3 head_local(0, 0, 0.5 * body.shape.length);
    slot_position[head_slot(b)] = body.head();
    slot_position[tail_slot(b)] = body.tail();
    slot_velocity[head_slot(b)] = body.velocity_at(head_local);
    slot_velocity[tail_slot(b)] = body.velocity_at(-head_local);
    slot_mass[head_slot(b)] = limb_masses[b].head;
    slot_mass[tail_slot(b)] = limb_masses[b].tail;
    if (centres) {
      slot_position[centre_slot(b)] = body.position;
      slot_velocity[centre_slot(b)] = body.linear_velocity;
      slot_mass[centre_slot(b)] = limb_masses[b].centre;
    }
    if (frame_plan.framed[b]) {
      for (int side = 0; side < 2; ++side) {
        const Vector3 local = (side == 0 ? 1.0 : -1.0) * frame_plan.spacing[b] * frame_plan.direction[b];
        slot_position[frame_slot(b, side)] = body.to_world(local);
        slot_velocity[frame_slot(b, side)] = body.velocity_at(local);
        slot_mass[frame_slot(b, side)] = frame_plan.frame_mass[b];
      }
    }
  }
  for (std::size_t k = 0; k < joint_count; ++k) {
    if (model.joints[k].inboard != kWorld) continue;
    slot_position[pin_slot_of_joint[k]] = model.joints[k].inboard_anchor;
    slot_pinned[pin_slot_of_joint[k]] = true;
  }

  // Merge slots joined by shared-particle joints (a world joint pins the body's own end).
  DisjointSets merged(slot_count);
  if (shared) {
    for (std::size_t k = 0; k < joint_count; ++k) merged.unite(joint_inboard_slot[k], joint_outboard_slot[k]);
  }

  // Islands: the Model's (body_islands). Per body: its (joint, other body) neighbours and its
  // joints to the world.
  const BodyIslands islands = body_islands(model);
  using Neighbour = std::pair<std::uint32_t, std::uint32_t>;
  std::vector<std::pair<std::uint32_t, Neighbour>> neighbour_pairs;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> world_joint_pairs;
  for (std::size_t k = 0; k < joint_count; ++k) {
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
  const CompressedRows<Neighbour> neighbours = group_by_row(body_count, neighbour_pairs);
  const CompressedRows<std::uint32_t> world_joints = group_by_row(body_count, world_joint_pairs);

  // Each island starts from its first body held by the world, else its first body.
  std::vector<std::uint32_t> island_root(islands.count);
  for (std::size_t b = body_count; b-- > 0;) {  // descending, so the lowest (held) body wins
    island_root[islands.island_of_body[b]] = static_cast<std::uint32_t>(b);
  }
  for (std::size_t b = body_count; b-- > 0;) {
    if (!world_joints.row(b).empty()) island_root[islands.island_of_body[b]] = static_cast<std::uint32_t>(b);
  }

  // Breadth-first order of each island's bodies from its root, and the tree joint reaching each.
  // body_order doubles as the search queue; island i's bodies are body_order[island_begin[i] ..
  // island_begin[i + 1]).
  std::vector<std::uint32_t> body_order, island_begin;
  body_order.reserve(body_count);
  std::vector<std::int64_t> tree_joint(body_count, -1);
  std::vector<bool> visited(body_count, false);
  for (std::size_t island = 0; island < islands.count; ++island) {
    island_begin.push_back(static_cast<std::uint32_t>(body_order.size()));
    const std::uint32_t root = island_root[island];
    body_order.push_back(root);
    visited[root] = true;
    for (std::size_t next = island_begin.back(); next < body_order.size(); ++next) {
      for (const auto& [joint, other] : neighbours.row(body_order[next])) {
        if (visited[other]) continue;
        visited[other] = true;
        tree_joint[other] = joint;
        body_order.push_back(other);
      }
    }
  }
  island_begin.push_back(static_cast<std::uint32_t>(body_order.size()));
  const std::size_t island_count = island_begin.size() - 1;
  const auto island_bodies = [&](std::size_t island) {
    return std::span<const std::uint32_t>(body_order.data() + island_begin[island], body_order.data() + island_begin[island + 1]);
  };

  // Particles, island by island, body by body (pins first, then head, centre, tail).
  const std::uint32_t unassigned = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> particle_of_root(slot_count, unassigned);
  std::vector<std::uint32_t> first_slot_of_particle;
  auto assign = [&](std::uint32_t slot) {
    const std::uint32_t root = merged.find(slot);
    if (particle_of_root[root] == unassigned) {
      particle_of_root[root] = checked_index(first_slot_of_particle.size());
      first_slot_of_particle.push_back(slot);
    }
  };
  std::vector<std::uint32_t> island_particle_end;
  for (std::size_t island = 0; island < island_count; ++island) {
    for (std::uint32_t b : island_bodies(island)) {
      if (!shared) for (std::uint32_t k : world_joints.row(b)) assign(pin_slot_of_joint[k]);
      assign(head_slot(b));
      if (centres) assign(centre_slot(b));
      assign(tail_slot(b));
      if (frame_plan.framed[b]) assign(frame_slot(b, 0)), assign(frame_slot(b, 1));
    }
    island_particle_end.push_back(checked_index(first_slot_of_particle.size()));
  }
  auto particle_of = [&](std::uint32_t slot) { return particle_of_root[merged.find(slot)]; };

  const std::size_t body_particle_count = first_slot_of_particle.size();
  const std::size_t particle_count = body_particle_count + model.balls.size();
  state.particles.resize(particle_count);
  state.particle_mass.assign(particle_count, 0.0);

  // Merge slot properties into particles: masses add, positions and velocities average by mass
  // (momentum is kept); a pin wins.
  std::vector<Vector3> momentum(body_particle_count, Vector3::Zero());
  std::vector<Vector3> mass_weighted_position(body_particle_count, Vector3::Zero());
  std::vector<bool> pinned(body_particle_count, false);
  std::vector<Vector3> pin_position(body_particle_count, Vector3::Zero());
  for (std::size_t slot = 0; slot < slot_count; ++slot) {
    const std::uint32_t p = particle_of(static_cast<std::uint32_t>(slot));
    if (p == unassigned) continue;
    state.particle_mass[p] += slot_mass[slot];
    momentum[p] += slot_mass[slot] * slot_velocity[slot];
    mass_weighted_position[p] += slot_mass[slot] * slot_position[slot];
    if (slot_pinned[slot]) pinned[p] = true, pin_position[p] = slot_position[slot];
  }
  for (std::size_t p = 0; p < body_particle_count; ++p) {
    const double mass = state.particle_mass[p];
    Vector3 position = mass > 0 ? Vector3(mass_weighted_position[p] / mass) : slot_position[first_slot_of_particle[p]];
    Vector3 velocity = mass > 0 ? Vector3(momentum[p] / mass) : Vector3::Zero();
    if (pinned[p]) position = pin_position[p], velocity.setZero();
    if (!pinned[p] && !(mass > 0)) {  // only limb_masses "lumps" leaves an end without mass
      const std::uint32_t slot = first_slot_of_particle[p];
      std::ostringstream message;
      message << "bodies[" << slot / slots_per_body << "] '" << model.bodies[slot / slots_per_body].name
              << "': limb_masses \"lumps\" leaves its " << (slot % slots_per_body == 0 ? "head" : "tail")
              << " without mass, and no joint shares that particle with a massive one or pins it; put a point mass "
                 "there, or join it with \"joints\": \"shared_particle\"";
      throw ModelError(message.str());
    }
    state.particles.set_position(p, position.cast<Scalar>());
    state.particles.set_previous(p, (position - velocity * dt).cast<Scalar>());
    if (rattle) state.particles.set_velocity(p, velocity.cast<Scalar>());
    state.particles.inverse_mass[p] = pinned[p] ? Scalar(0) : Scalar(1.0 / mass);
  }

  // Constraints and limbs, island by island in the same breadth-first order: each body's tree
  // joint (or world pins) before its link, so a sweep runs from the root outwards. A centre
  // particle hangs on the half-length constraints head–centre and centre–tail; the head–tail
  // link stays, so the limb's length does not depend on how well the centre has converged.
  std::vector<std::array<std::uint32_t, 2>> pairs;
  std::vector<double> rest;
  auto add_constraint = [&](std::uint32_t i, std::uint32_t j, double length) {
    pairs.push_back({i, j});
    rest.push_back(length);
    return checked_index(pairs.size() - 1);
  };
  auto add_joint_constraint = [&](std::size_t k) {
    if (shared || frame_plan.point_row[k]) return;  // a point row holds it (frames.hpp)
    const Joint& joint = model.joints[k];
    double reference = model.bodies[joint.outboard].shape.length;
    if (joint.inboard != kWorld) reference = 0.5 * (reference + model.bodies[joint.inboard].shape.length);
    const std::uint32_t c = add_constraint(particle_of(joint_inboard_slot[k]), particle_of(joint_outboard_slot[k]), 0.0);
    state.joint_constraints.emplace_back(c, reference);
  };
  std::vector<bool> joint_done(joint_count, false);
  state.body_limb.assign(body_count, 0);
  std::uint32_t particle_begin = 0;
  for (std::size_t island_index = 0; island_index < island_count; ++island_index) {
    Island island;
    island.particle_begin = particle_begin;
    island.particle_end = particle_begin = island_particle_end[island_index];
    island.constraint_begin = checked_index(pairs.size());
    island.limb_begin = checked_index(state.limbs.size());
    for (std::uint32_t b : island_bodies(island_index)) {
      for (std::uint32_t k : world_joints.row(b)) add_joint_constraint(k), joint_done[k] = true;
      if (tree_joint[b] >= 0) add_joint_constraint(static_cast<std::size_t>(tree_joint[b])), joint_done[tree_joint[b]] = true;
      const Body& body = model.bodies[b];
      const std::uint32_t head = particle_of(head_slot(b)), tail = particle_of(tail_slot(b));
      const std::uint32_t centre = centres ? particle_of(centre_slot(b)) : kNoCentre;
      state.body_limb[b] = checked_index(state.limbs.size());
      state.limbs.head.push_back(head);
      state.limbs.tail.push_back(tail);
      state.limbs.centre.push_back(centre);
      state.limbs.link_constraint.push_back(add_constraint(head, tail, body.shape.length));
      if (centres) {
        add_constraint(head, centre, 0.5 * body.shape.length);
        add_constraint(centre, tail, 0.5 * body.shape.length);
      }
      if (frame_plan.framed[b]) {  // the triangle head, tail, F⁺ (F⁻ by the frame's point row)
        const double diagonal = std::hypot(0.5 * body.shape.length, frame_plan.spacing[b]);
        add_constraint(head, particle_of(frame_slot(b, 0)), diagonal);
        add_constraint(tail, particle_of(frame_slot(b, 0)), diagonal);
      }
      state.limbs.head_mass.push_back(limb_masses[b].head);
      state.limbs.centre_mass.push_back(limb_masses[b].centre);
      state.limbs.tail_mass.push_back(limb_masses[b].tail);
      state.limbs.radius.push_back(body.shape.radius);
      state.limbs.shape.push_back(body.shape.type);
    }
    // Joints that close loops inside the island come last.
    for (std::uint32_t b : island_bodies(island_index)) {
      for (const auto& neighbour : neighbours.row(b)) {
        if (!joint_done[neighbour.first]) add_joint_constraint(neighbour.first), joint_done[neighbour.first] = true;
      }
    }
    island.constraint_end = checked_index(pairs.size());
    island.limb_end = checked_index(state.limbs.size());
    state.islands.push_back(island);
  }
  state.constraints.resize(pairs.size(), state.particles.null_particle());
  for (std::size_t c = 0; c < pairs.size(); ++c) {
    state.constraints.particle_i[c] = pairs[c][0];
    state.constraints.particle_j[c] = pairs[c][1];
    state.constraints.rest_length[c] = static_cast<Scalar>(rest[c]);
  }
  // Where each particle comes from (for names in outputs): the first slot that created it.
  std::vector<std::uint32_t> joint_of_pin_slot(slot_count - pin_slot_base);
  for (std::size_t k = 0; k < joint_count; ++k) {
    if (model.joints[k].inboard == kWorld) joint_of_pin_slot[pin_slot_of_joint[k] - pin_slot_base] = static_cast<std::uint32_t>(k);
  }
  state.particle_origins.resize(particle_count);
  for (std::size_t p = 0; p < body_particle_count; ++p) {
    const std::uint32_t slot = first_slot_of_particle[p];
    const std::uint32_t offset = slot % slots_per_body;
    const ParticleOrigin::Kind kind = offset == 0                      ? ParticleOrigin::Kind::limb_head
                                      : offset == 1                    ? ParticleOrigin::Kind::limb_tail
                                      : offset == frame_slot_offset    ? ParticleOrigin::Kind::limb_frame_plus
                                      : offset == frame_slot_offset + 1 ? ParticleOrigin::Kind::limb_frame_minus
                                                                       : ParticleOrigin::Kind::limb_centre;
    state.particle_origins[p] = slot < pin_slot_base
        ? ParticleOrigin{slot / slots_per_body, kind}
        : ParticleOrigin{joint_of_pin_slot[slot - pin_slot_base], ParticleOrigin::Kind::world_pin};
  }

  // Each ball: one particle, its own island.
  for (std::size_t b = 0; b < model.balls.size(); ++b) {
    const Ball& ball = model.balls[b];
    const std::uint32_t p = checked_index(body_particle_count + b);
    state.balls.push_back({p, checked_index(state.islands.size()), ball.radius, ball.restitution});
    state.particle_origins[p] = {checked_index(b), ParticleOrigin::Kind::ball};
    state.particle_mass[p] = ball.mass;
    state.particles.set_position(p, ball.position.cast<Scalar>());
    state.particles.set_previous(p, (ball.position - ball.velocity * dt).cast<Scalar>());
    if (rattle) state.particles.set_velocity(p, ball.velocity.cast<Scalar>());
    state.particles.inverse_mass[p] = Scalar(1.0 / ball.mass);
    Island island;
    island.particle_begin = p;
    island.particle_end = p + 1;
    island.constraint_begin = island.constraint_end = checked_index(pairs.size());
    island.limb_begin = island.limb_end = checked_index(state.limbs.size());
    state.islands.push_back(island);
  }

  // Planes and the features that can touch them — only when the scene has something to touch.
  // A centre particle has none: the limb's surface is reached by its end features (a cylinder's
  // rims, a capsule's end spheres), and the centre follows through its constraints.
  state.planes = scene_planes(model);
  if (!state.planes.empty()) {
    for (Island& island : state.islands) {
      island.feature_begin = checked_index(state.features.size());
      for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) {
        const bool disk = state.limbs.shape[limb] == ShapeType::cylinder;
        const double radius = state.limbs.radius[limb];
        const std::uint32_t head = state.limbs.head[limb], tail = state.limbs.tail[limb];
        state.features.push_back({head, disk ? tail : head, radius, disk, 0.0, limb});
        state.features.push_back({tail, disk ? head : tail, radius, disk, 0.0, limb});
      }
      for (const BallParticle& ball : state.balls) {
        if (&island != &state.islands[ball.island]) continue;
        state.features.push_back({ball.particle, ball.particle, ball.radius, false, ball.restitution, kNoLimb});
      }
      island.feature_end = checked_index(state.features.size());
    }
  }

  // Scratch with its final capacity: step() never allocates.
  state.plane_contacts.reserve(state.features.size() * state.planes.size());
  state.ball_contacts.reserve(state.balls.size() * state.limbs.size());
  state.pending_forces.reserve(3 * 64);  // apply_force: up to 64 forces, each over ≤ 3 particles
  state.kinematic_targets.reserve(64);
  state.awake_islands.reserve(state.islands.size());
  state.contact_particles.reserve(2 * state.plane_contacts.capacity() + 3 * state.ball_contacts.capacity() +
                                  (centres ? 3 * state.limbs.size() : 0));

  // The thesis's standing humanoid: islands at rest start asleep and wait for a contact.
  for (Island& island : state.islands) {
    bool at_rest = true;
    for (std::uint32_t p = island.particle_begin; p < island.particle_end; ++p) {
      at_rest = at_rest && state.particles.position(p) == state.particles.previous(p);
    }
    island.sleeping = model.settings.sleep.enabled && model.settings.sleep.start_asleep && at_rest;
  }
  // Joint rows (frames.hpp), on the particles as numbered so far; renumbering rewrites them.
  state.joint_controls = joint_controls(model);
  if (frame_plan.any_rows) {
    const std::uint32_t null_particle = state.particles.null_particle();
    state.joint_rows = frames::build_rows(
        model, frame_plan,
        [&](std::size_t b) {
          frames::LimbParticles p;
          p.fill(null_particle);
          p[0] = particle_of(head_slot(b)), p[1] = particle_of(tail_slot(b));
          if (frame_plan.framed[b]) p[2] = particle_of(frame_slot(b, 0)), p[3] = particle_of(frame_slot(b, 1));
          if (centres) p[4] = particle_of(centre_slot(b));
          return p;
        },
        [&](std::size_t k) { return particle_of(pin_slot_of_joint[k]); },
        [&](std::size_t b) { return islands.island_of_body[b]; }, null_particle);
  }
  rebuild_awake_islands(state);
  renumber_particles(state);
  prepare_relaxation_plan(state);
  prepare_limb_collisions(state, model);
  // The body frames: each body's Model orientation, turned onto its limb's axis as compiled.
  for (const Body& body : model.bodies) state.body_frame.push_back(body.orientation());
  transport_body_frames(state);
  return state;
}

std::string particle_name(const Model& model, const ParticleOrigin& origin) {
  switch (origin.kind) {
    case ParticleOrigin::Kind::limb_head: return model.bodies[origin.index].name + ".head";
    case ParticleOrigin::Kind::limb_tail: return model.bodies[origin.index].name + ".tail";
    case ParticleOrigin::Kind::limb_centre: return model.bodies[origin.index].name + ".centre";
    case ParticleOrigin::Kind::limb_frame_plus: return model.bodies[origin.index].name + ".frame+";
    case ParticleOrigin::Kind::limb_frame_minus: return model.bodies[origin.index].name + ".frame-";
    case ParticleOrigin::Kind::world_pin: return model.joints[origin.index].name + ".pin";
    case ParticleOrigin::Kind::ball: return ball_name(model, origin.index);
  }
  return "?";
}

template VerletState<float> compile<float>(const Model&, const VerletOptions&);
template VerletState<double> compile<double>(const Model&, const VerletOptions&);

}  // namespace limber
