#include "kernel/verlet/compile.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>

#include "kernel/relaxation/relaxation.hpp"
#include "kernel/sleeping/sleeping.hpp"
#include "layouts/graph/compressed_rows.hpp"
#include "layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

enum class End : std::uint8_t { head, tail };

// Which axis end point a joint anchor is; the particle method has particles only there.
End anchor_end(const Model& model, std::size_t joint_index, bool inboard) {
  const Joint& joint = model.joints[joint_index];
  const Body& body = model.bodies[inboard ? joint.inboard : joint.outboard];
  const Vector3& anchor = inboard ? joint.inboard_anchor : joint.outboard_anchor;
  const double half = 0.5 * body.shape.length;
  const double tolerance = 1e-9 * std::max(1.0, body.shape.length);
  if ((anchor - Vector3(0, 0, half)).norm() <= tolerance) return End::head;
  if ((anchor - Vector3(0, 0, -half)).norm() <= tolerance) return End::tail;
  std::ostringstream message;
  message << "joints[" << joint_index << "] '" << joint.name << "'."
          << (inboard ? "inboard_anchor" : "outboard_anchor") << ": the particle (Verlet) method joins limbs only "
          << "at their axis end points, \"head\" (0, 0, " << half << ") or \"tail\" (0, 0, " << -half << ") of body '"
          << body.name << "'; got (" << anchor.x() << ", " << anchor.y() << ", " << anchor.z() << ")";
  throw ModelError(message.str());
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
  for (auto* list : {&state.limbs.head, &state.limbs.tail}) {
    for (std::uint32_t& p : *list) p = new_index[p];
  }
  for (ContactFeature& feature : state.features) {
    feature.particle = new_index[feature.particle], feature.axis_partner = new_index[feature.axis_partner];
  }
  if (state.ball_particle >= 0) state.ball_particle = new_index[static_cast<std::size_t>(state.ball_particle)];
}

}  // namespace

template <typename Scalar>
VerletState<Scalar> compile(const Model& model, const VerletOptions& options) {
  validate(model);
  const std::size_t body_count = model.bodies.size();
  const std::size_t joint_count = model.joints.size();
  const bool shared = model.settings.verlet.joints == ParticleJoints::shared_particle;
  const double dt = model.settings.time_step;

  VerletState<Scalar> state;
  state.options = options;
  state.settings = model.settings;
  state.gravity = model.settings.gravity.cast<Scalar>();
  state.previous_time_step = dt;

  // Slots: every place a particle may sit. Body b has its head at 2b and tail at 2b+1; each joint
  // to the world has a pin slot after them. Shared-particle joints merge slots into one particle.
  const std::size_t pin_slot_base = 2 * body_count;
  std::vector<std::uint32_t> joint_inboard_slot(joint_count), joint_outboard_slot(joint_count);
  std::vector<std::uint32_t> pin_slot_of_joint(joint_count, 0);
  std::size_t slot_count = pin_slot_base;
  for (std::size_t k = 0; k < joint_count; ++k) {
    const Joint& joint = model.joints[k];
    const End outboard_end = anchor_end(model, k, false);
    joint_outboard_slot[k] = checked_index(2 * joint.outboard + (outboard_end == End::tail));
    if (joint.inboard == kWorld) {
      pin_slot_of_joint[k] = checked_index(slot_count++);
      joint_inboard_slot[k] = pin_slot_of_joint[k];
    } else {
      joint_inboard_slot[k] = checked_index(2 * joint.inboard + (anchor_end(model, k, true) == End::tail));
    }
  }

  // Slot positions, velocities, mass shares, pins.
  std::vector<Vector3> slot_position(slot_count), slot_velocity(slot_count, Vector3::Zero());
  std::vector<double> slot_mass(slot_count, 0.0);
  std::vector<bool> slot_pinned(slot_count, false);
  for (std::size_t b = 0; b < body_count; ++b) {
    const Body& body = model.bodies[b];
    const Vector3 head_local(0, 0, 0.5 * body.shape.length);
    slot_position[2 * b] = body.head();
    slot_position[2 * b + 1] = body.tail();
    slot_velocity[2 * b] = body.velocity_at(head_local);
    slot_velocity[2 * b + 1] = body.velocity_at(-head_local);
    slot_mass[2 * b] = slot_mass[2 * b + 1] = 0.5 * body.mass;
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

  // Islands: bodies connected through joints (the world does not connect them). Per body: its
  // (joint, other body) neighbours and its joints to the world.
  DisjointSets connected(body_count);
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
    connected.unite(inboard, outboard);
    neighbour_pairs.push_back({inboard, {j, outboard}});
    neighbour_pairs.push_back({outboard, {j, inboard}});
  }
  const CompressedRows<Neighbour> neighbours = group_by_row(body_count, neighbour_pairs);
  const CompressedRows<std::uint32_t> world_joints = group_by_row(body_count, world_joint_pairs);

  // Each island starts from its first body held by the world, else its first body. The union-find
  // representative of an island is its lowest body index.
  std::vector<std::uint32_t> island_root(body_count);
  for (std::uint32_t b = 0; b < body_count; ++b) island_root[b] = b;  // read only at representatives
  for (std::size_t b = body_count; b-- > 0;) {  // descending, so the lowest held body wins
    if (!world_joints.row(b).empty()) island_root[connected.find(static_cast<std::uint32_t>(b))] = static_cast<std::uint32_t>(b);
  }

  // Breadth-first order of each island's bodies from its root, and the tree joint reaching each.
  // body_order doubles as the search queue; island i's bodies are body_order[island_begin[i] ..
  // island_begin[i + 1]).
  std::vector<std::uint32_t> body_order, island_begin;
  body_order.reserve(body_count);
  std::vector<std::int64_t> tree_joint(body_count, -1);
  std::vector<bool> visited(body_count, false);
  for (std::size_t b = 0; b < body_count; ++b) {
    if (connected.find(static_cast<std::uint32_t>(b)) != b) continue;  // one search per island
    island_begin.push_back(static_cast<std::uint32_t>(body_order.size()));
    const std::uint32_t root = island_root[b];
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

  // Particles, island by island, body by body (pins first, then head, tail).
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
      assign(2 * b);
      assign(2 * b + 1);
    }
    island_particle_end.push_back(checked_index(first_slot_of_particle.size()));
  }
  auto particle_of = [&](std::uint32_t slot) { return particle_of_root[merged.find(slot)]; };

  const std::size_t body_particle_count = first_slot_of_particle.size();
  const bool has_ball = model.ball.has_value();
  const std::size_t particle_count = body_particle_count + (has_ball ? 1 : 0);
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
    state.particles.set_position(p, position.cast<Scalar>());
    state.particles.set_previous(p, (position - velocity * dt).cast<Scalar>());
    state.particles.inverse_mass[p] = pinned[p] || mass <= 0 ? Scalar(0) : Scalar(1.0 / mass);
  }

  // Constraints and limbs, island by island in the same breadth-first order: each body's tree
  // joint (or world pins) before its link, so a sweep runs from the root outwards.
  std::vector<std::array<std::uint32_t, 2>> pairs;
  std::vector<double> rest;
  auto add_constraint = [&](std::uint32_t i, std::uint32_t j, double length) {
    pairs.push_back({i, j});
    rest.push_back(length);
    return checked_index(pairs.size() - 1);
  };
  auto add_joint_constraint = [&](std::size_t k) {
    if (shared) return;
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
      const std::uint32_t head = particle_of(2 * b), tail = particle_of(2 * b + 1);
      state.body_limb[b] = checked_index(state.limbs.size());
      state.limbs.head.push_back(head);
      state.limbs.tail.push_back(tail);
      state.limbs.link_constraint.push_back(add_constraint(head, tail, body.shape.length));
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
    state.particle_origins[p] = slot < pin_slot_base
        ? ParticleOrigin{slot / 2, slot % 2 ? ParticleOrigin::Kind::limb_tail : ParticleOrigin::Kind::limb_head}
        : ParticleOrigin{joint_of_pin_slot[slot - pin_slot_base], ParticleOrigin::Kind::world_pin};
  }

  // The ball: one particle, its own island.
  if (has_ball) {
    const Ball& ball = *model.ball;
    const std::uint32_t p = checked_index(body_particle_count);
    state.ball_particle = p;
    state.particle_origins[p] = {0, ParticleOrigin::Kind::ball};
    state.ball_radius = ball.radius;
    state.ball_restitution = ball.restitution;
    state.particle_mass[p] = ball.mass;
    state.particles.set_position(p, ball.position.cast<Scalar>());
    state.particles.set_previous(p, (ball.position - ball.velocity * dt).cast<Scalar>());
    state.particles.inverse_mass[p] = Scalar(1.0 / ball.mass);
    Island island;
    island.particle_begin = p;
    island.particle_end = p + 1;
    island.constraint_begin = island.constraint_end = checked_index(pairs.size());
    island.limb_begin = island.limb_end = checked_index(state.limbs.size());
    state.ball_island = static_cast<std::int64_t>(state.islands.size());
    state.islands.push_back(island);
  }

  // Planes and the features that can touch them — only when the scene has something to touch.
  if (model.ground) {
    state.planes.push_back({Eigen::Vector3d::UnitZ(), model.ground->height, model.ground->restitution,
                            model.ground->friction});
  }
  if (model.bounds) {
    const Bounds& box = *model.bounds;
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d normal = Eigen::Vector3d::Unit(axis);
      state.planes.push_back({normal, box.min[axis], box.restitution, box.friction});
      state.planes.push_back({-normal, -box.max[axis], box.restitution, box.friction});
    }
  }
  if (!state.planes.empty()) {
    for (Island& island : state.islands) {
      island.feature_begin = checked_index(state.features.size());
      for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) {
        const bool disk = state.limbs.shape[limb] == ShapeType::cylinder;
        const double radius = state.limbs.radius[limb];
        const std::uint32_t head = state.limbs.head[limb], tail = state.limbs.tail[limb];
        state.features.push_back({head, disk ? tail : head, radius, disk, 0.0});
        state.features.push_back({tail, disk ? head : tail, radius, disk, 0.0});
      }
      if (state.ball_island >= 0 && &island == &state.islands[state.ball_island]) {
        const auto p = static_cast<std::uint32_t>(state.ball_particle);
        state.features.push_back({p, p, state.ball_radius, false, state.ball_restitution});
      }
      island.feature_end = checked_index(state.features.size());
    }
  }

  // Scratch with its final capacity: step() never allocates.
  state.plane_contacts.reserve(state.features.size() * state.planes.size());
  state.ball_contacts.reserve(has_ball ? state.limbs.size() : 0);
  state.pending_forces.reserve(64);
  state.awake_islands.reserve(state.islands.size());
  state.contact_particles.reserve(2 * state.plane_contacts.capacity() + 3 * state.ball_contacts.capacity());

  // The thesis's standing humanoid: islands at rest start asleep and wait for a contact.
  for (Island& island : state.islands) {
    bool at_rest = true;
    for (std::uint32_t p = island.particle_begin; p < island.particle_end; ++p) {
      at_rest = at_rest && state.particles.position(p) == state.particles.previous(p);
    }
    island.sleeping = model.settings.sleep.enabled && model.settings.sleep.start_asleep && at_rest;
  }
  rebuild_awake_islands(state);
  renumber_particles(state);
  prepare_relaxation_plan(state);
  return state;
}

std::string particle_name(const Model& model, const ParticleOrigin& origin) {
  switch (origin.kind) {
    case ParticleOrigin::Kind::limb_head: return model.bodies[origin.index].name + ".head";
    case ParticleOrigin::Kind::limb_tail: return model.bodies[origin.index].name + ".tail";
    case ParticleOrigin::Kind::world_pin: return model.joints[origin.index].name + ".pin";
    case ParticleOrigin::Kind::ball: return "ball";
  }
  return "?";
}

template VerletState<float> compile<float>(const Model&, const VerletOptions&);
template VerletState<double> compile<double>(const Model&, const VerletOptions&);

}  // namespace limber
