#include "limber/kernel/verlet/compile.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <sstream>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/scene/capsule_proxy.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"
#include "limber/kernel/verlet/bodies.hpp"
#include "limber/kernel/verlet/frames.hpp"
#include "limber/kernel/verlet/particle_plan.hpp"
#include "limber/layouts/graph/compressed_rows.hpp"
#include "limber/layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

using particle_plan::checked_index;
using particle_plan::Plan;

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

// --- The state from the plan (particle_plan.hpp plans the particles first): compile's passes.

// Merge slot properties into particles: masses add, positions and velocities average by mass
// (momentum is kept); a pin wins. x* = x − v·Δt, and v under rattle.
template <typename Scalar>
void place_particles(VerletState<Scalar>& state, const Model& model, const Plan& plan) {
  const std::size_t body_particle_count = plan.body_particle_count();
  const std::size_t particle_count = body_particle_count + model.balls.size();
  state.particles.resize(particle_count);
  state.particle_mass.assign(particle_count, 0.0);
  const double dt = model.settings.time_step;
  const bool rattle = state.options.relaxation.projection == ProjectionRule::rattle;
  const std::size_t slot_count = plan.slot_count, slots_per_body = plan.slots_per_body;
  const std::vector<Vector3>& slot_position = plan.slot_position;
  const std::vector<Vector3>& slot_velocity = plan.slot_velocity;
  const std::vector<double>& slot_mass = plan.slot_mass;
  const std::vector<bool>& slot_pinned = plan.slot_pinned;
  const std::vector<std::uint32_t>& first_slot_of_particle = plan.first_slot_of_particle;
  const std::uint32_t unassigned = Plan::kUnassigned;
  const auto particle_of = [&](std::uint32_t slot) { return plan.particle_of(slot); };
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
}

// Constraints and limbs, island by island in the same breadth-first order: each body's tree
// joint (or world pins) before its link, so a sweep runs from the root outwards. A centre
// particle hangs on the half-length constraints head–centre and centre–tail; the head–tail
// link stays, so the limb's length does not depend on how well the centre has converged.
template <typename Scalar>
void build_constraints(VerletState<Scalar>& state, const Model& model, const Plan& plan) {
  const bool shared = plan.shared, centres = plan.centres;
  const frames::Plan& frame_plan = plan.frames;
  const auto particle_of = [&](std::uint32_t slot) { return plan.particle_of(slot); };
  const auto head_slot = [&](std::size_t b) { return plan.head_slot(b); };
  const auto tail_slot = [&](std::size_t b) { return plan.tail_slot(b); };
  const auto centre_slot = [&](std::size_t b) { return plan.centre_slot(b); };
  const auto frame_slot = [&](std::size_t b, int side) { return plan.frame_slot(b, side); };
  const std::size_t body_count = model.bodies.size(), joint_count = model.joints.size(), island_count = plan.island_count();
  const auto& world_joints = plan.world_joints;
  const auto& neighbours = plan.neighbours;
  const auto& tree_joint = plan.tree_joint;
  const auto& island_particle_end = plan.island_particle_end;
  const auto& limb_masses = plan.limb_masses;
  const auto island_bodies = [&](std::size_t island) { return plan.island_bodies(island); };
  const auto& joint_inboard_slot = plan.joint_inboard_slot;
  const auto& joint_outboard_slot = plan.joint_outboard_slot;
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
    double reference = frames::axis_length(model.bodies[joint.outboard]);
    if (joint.inboard != kWorld) reference = 0.5 * (reference + frames::axis_length(model.bodies[joint.inboard]));
    const std::uint32_t c = add_constraint(particle_of(joint_inboard_slot[k]), particle_of(joint_outboard_slot[k]), 0.0);
    state.joint_constraints.emplace_back(c, reference);
    state.joint_constraint_joint.push_back(static_cast<std::uint32_t>(k));
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
      const double length = frames::axis_length(body);
      const std::uint32_t head = particle_of(head_slot(b)), tail = particle_of(tail_slot(b));
      const std::uint32_t centre = centres ? particle_of(centre_slot(b)) : kNoCentre;
      state.body_limb[b] = checked_index(state.limbs.size());
      state.limbs.head.push_back(head);
      state.limbs.tail.push_back(tail);
      state.limbs.centre.push_back(centre);
      state.limbs.link_constraint.push_back(add_constraint(head, tail, length));
      if (centres) {
        add_constraint(head, centre, 0.5 * length);
        add_constraint(centre, tail, 0.5 * length);
      }
      if (frame_plan.framed[b]) {  // the triangle head, tail, F⁺ (F⁻ by the frame's point row)
        const double diagonal = std::hypot(0.5 * length, frame_plan.spacing[b]);
        add_constraint(head, particle_of(frame_slot(b, 0)), diagonal);
        add_constraint(tail, particle_of(frame_slot(b, 0)), diagonal);
      }
      state.limbs.head_mass.push_back(limb_masses[b].head);
      state.limbs.centre_mass.push_back(limb_masses[b].centre);
      state.limbs.tail_mass.push_back(limb_masses[b].tail);
      state.limbs.radius.push_back(body.shape.radius);
      state.limbs.shape.push_back(body.shape.type);
      state.limbs.sphere.push_back(body.shape.length > 0 ? 0 : 1);
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
}

// Where each particle comes from (for names in outputs): the first slot that created it.
template <typename Scalar>
void record_particle_origins(VerletState<Scalar>& state, const Model& model, const Plan& plan) {
  const std::size_t joint_count = model.joints.size(), slot_count = plan.slot_count, pin_slot_base = plan.pin_slot_base;
  const std::size_t body_particle_count = plan.body_particle_count();
  const std::size_t particle_count = body_particle_count + model.balls.size();
  const std::uint32_t slots_per_body = plan.slots_per_body, frame_slot_offset = plan.frame_slot_offset;
  const auto& pin_slot_of_joint = plan.pin_slot_of_joint;
  const auto& first_slot_of_particle = plan.first_slot_of_particle;
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
}

// Each ball: one particle, its own island.
template <typename Scalar>
void add_balls(VerletState<Scalar>& state, const Model& model, const Plan& plan) {
  const std::size_t body_particle_count = plan.body_particle_count();
  const double dt = model.settings.time_step;
  const bool rattle = state.options.relaxation.projection == ProjectionRule::rattle;
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
    island.constraint_begin = island.constraint_end = checked_index(state.constraints.size());
    island.limb_begin = island.limb_end = checked_index(state.limbs.size());
    state.islands.push_back(island);
  }
}

// Planes and the features that can touch them — only when the scene has something to touch.
// A centre particle has none: the limb's surface is reached by its end features (a cylinder's
// rims, a capsule's end spheres), and the centre follows through its constraints.
template <typename Scalar>
void add_plane_features(VerletState<Scalar>& state, const Model& model) {
  state.planes = scene_planes(model);
  if (!state.planes.empty()) {
    for (Island& island : state.islands) {
      island.feature_begin = checked_index(state.features.size());
      for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) {
        const bool disk = state.limbs.shape[limb] == ShapeType::cylinder;
        const double radius = state.limbs.radius[limb];
        const std::uint32_t head = state.limbs.head[limb], tail = state.limbs.tail[limb];
        if (state.limbs.sphere[limb]) {  // one sphere about its centre
          state.features.push_back({head, tail, radius, false, 0.0, limb, /*at_centre=*/true});
          continue;
        }
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
}

// Scratch with its final capacity: step() never allocates.
template <typename Scalar>
void reserve_scratch(VerletState<Scalar>& state, const Plan& plan) {
  const bool centres = plan.centres;
  state.plane_contacts.reserve(state.features.size() * state.planes.size());
  state.ball_contacts.reserve(state.balls.size() * state.limbs.size());
  state.pending_forces.reserve(3 * 64);  // apply_force: up to 64 forces, each over ≤ 3 particles
  state.kinematic_targets.reserve(64);
  state.awake_islands.reserve(state.islands.size());
  state.contact_particles.reserve(2 * state.plane_contacts.capacity() + 3 * state.ball_contacts.capacity() +
                                  (centres ? 3 * state.limbs.size() : 0));
}

// The thesis's standing humanoid: islands at rest start asleep and wait for a contact.
template <typename Scalar>
void start_asleep_at_rest(VerletState<Scalar>& state, const Model& model) {
  for (Island& island : state.islands) {
    bool at_rest = true;
    for (std::uint32_t p = island.particle_begin; p < island.particle_end; ++p) {
      at_rest = at_rest && state.particles.position(p) == state.particles.previous(p);
    }
    island.sleeping = model.settings.sleep.enabled && model.settings.sleep.start_asleep && at_rest;
  }
}

// Joint rows (frames.hpp), on the particles as numbered so far; renumbering rewrites them.
template <typename Scalar>
void build_joint_rows(VerletState<Scalar>& state, const Model& model, const Plan& plan) {
  state.joint_controls = joint_controls(model);
  if (!plan.frames.any_rows) return;
  const std::uint32_t null_particle = state.particles.null_particle();
  state.joint_rows = frames::build_rows(
      model, plan.frames,
      [&](std::size_t b) {
        frames::LimbParticles p;
        p.fill(null_particle);
        p[0] = plan.particle_of(plan.head_slot(b)), p[1] = plan.particle_of(plan.tail_slot(b));
        if (plan.frames.framed[b]) p[2] = plan.particle_of(plan.frame_slot(b, 0)), p[3] = plan.particle_of(plan.frame_slot(b, 1));
        if (plan.centres) p[4] = plan.particle_of(plan.centre_slot(b));
        return p;
      },
      [&](std::size_t k) { return plan.particle_of(plan.pin_slot_of_joint[k]); },
      [&](std::size_t b) { return plan.islands.island_of_body[b]; }, null_particle);
}

}  // namespace

// The passes in order (kernel/PIPELINE.md lists them): check, plan the particles, fill the state,
// then number, colour and prepare what the step needs.
template <typename Scalar>
VerletState<Scalar> compile(const Model& given, const VerletOptions& options) {
  validate(given);
  // Boxes and ellipsoids collide as their capsule proxies (capsule_proxy.hpp), on a copy.
  std::optional<Model> proxies;
  if (has_box_or_ellipsoid(given)) proxies = with_capsule_proxies(given);
  const Model& input = proxies ? *proxies : given;
  validate(options.relaxation);
  validate(options.verlet);
  require_supported(input, Method::particles);
  // Serial joints run as revolute joints through virtual links (serial_links.hpp), and anchors
  // that may move without changing their joints move into their limbs' frame planes
  // (frames::place_anchors). Either makes a copy of the Model; neither, none.
  std::optional<SerialExpansion> expansion;
  if (needs_serial_expansion(input)) expansion = expand_serial_joints(input);
  CoordinateAxes coordinate_axes;  // motors' axes (Model::actuators)
  if (!input.actuators.empty()) coordinate_axes = expansion ? CoordinateAxes::of(*expansion) : CoordinateAxes::of(input);
  std::optional<Model> placed;
  if (frames::anchors_to_place(expansion ? expansion->model : input)) {
    placed = expansion ? std::move(expansion->model) : input;
    frames::place_anchors(*placed);
  }
  const Model& model = placed ? *placed : expansion ? expansion->model : input;
  if (expansion) validate(model), require_supported(model, Method::particles);
  require_joint_controls(model, {true, true, true}, "verlet");

  Plan plan;
  particle_plan::plan_limb_masses(model, options, plan);
  particle_plan::plan_slots(model, plan);
  particle_plan::place_slots(model, plan);
  particle_plan::plan_islands(model, plan);
  particle_plan::number_particles(model, plan);

  VerletState<Scalar> state;
  state.options = options;
  state.settings = model.settings;
  state.gravity = model.settings.gravity.cast<Scalar>();
  state.previous_time_step = model.settings.time_step;
  state.coordinate_axes = std::move(coordinate_axes);
  place_particles(state, model, plan);
  build_constraints(state, model, plan);
  record_particle_origins(state, model, plan);
  add_balls(state, model, plan);
  add_plane_features(state, model);
  reserve_scratch(state, plan);
  start_asleep_at_rest(state, model);
  build_joint_rows(state, model, plan);

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
