#include "limber/kernel/collision/limb_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/collision/contacts.hpp"
#include "limber/kernel/geometry/time_of_impact.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"

namespace limber {
namespace {

// The speculative margin: every pair's floor, m, plus each segment's own reach — twice how far
// its ends moved this substep (so it finds what it may meet before the next search), capped
// (a reach past a limb's size finds nothing new).
constexpr double kMarginSlop = 0.005, kMaxReach = 0.5;

// How far a segment may move before the broadphase searches again, m: `ahead` substeps of its
// motion in this one, and the margin's slop more (a limb at rest set moving by a hit); a segment
// that moves further has the search run again (LimbCollisions::find_kept_pairs). With 1 cm the
// pile's searches were as many and its candidate pairs 4-12 % more; with none, 1.3-1.8 searches a step.
double search_reach(double motion, int ahead) {
  return ahead > 1 ? std::min(kMaxReach, ahead * motion + kMarginSlop) : std::min(kMaxReach, motion);
}

// Each Model body's segment at the predicted positions (then each ball's), with its reach (and
// for a search, `ahead` times it: the substeps it serves), and whether its island is awake.
template <typename Scalar>
void gather_segments(VerletState<Scalar>& state, int ahead) {
  const auto& p = state.particles;
  const LimbBuffer& limbs = state.limbs;
  const std::size_t bodies = state.body_limb.size();
  state.limb_segments.resize(bodies + state.balls.size());
  state.limb_awake.assign(state.limb_segments.size(), 0);
  for (std::uint32_t k : state.awake_islands) {
    const Island& island = state.islands[k];
    for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) state.limb_island_awake[limb] = 1;
  }
  const auto moved = [&](const Eigen::Vector3d& now, std::uint32_t particle) {
    return (now - p.previous(particle).template cast<double>()).norm();
  };
  for (std::size_t body = 0; body < bodies; ++body) {
    const std::uint32_t limb = state.body_limb[body], head = limbs.head[limb], tail = limbs.tail[limb];
    LimbSegment& segment = state.limb_segments[body];
    segment.head = p.position(head).template cast<double>();
    segment.tail = p.position(tail).template cast<double>();
    if (limbs.sphere[limb]) segment.head = segment.tail = 0.5 * (segment.head + segment.tail);  // a sphere: its centre
    segment.radius = limbs.radius[limb];
    state.limb_awake[body] = state.limb_island_awake[limb];
    const double motion = state.limb_awake[body] ? 2 * std::max(moved(segment.head, head), moved(segment.tail, tail)) : 0.0;
    segment.reach = std::min(kMaxReach, motion), segment.search_reach = search_reach(motion, ahead);
  }
  for (std::uint32_t k : state.awake_islands) {
    const Island& island = state.islands[k];
    for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) state.limb_island_awake[limb] = 0;
  }
  for (std::size_t b = 0; b < state.balls.size(); ++b) {
    const BallParticle& ball = state.balls[b];
    const auto index = static_cast<std::uint32_t>(bodies + b);
    LimbSegment& segment = state.limb_segments[index];
    segment.head = segment.tail = p.position(ball.particle).template cast<double>();
    segment.radius = ball.radius;
    state.limb_awake[index] = state.islands[ball.island].sleeping ? 0 : 1;
    const double motion = state.limb_awake[index] ? 2 * moved(segment.head, ball.particle) : 0.0;
    segment.reach = std::min(kMaxReach, motion), segment.search_reach = search_reach(motion, ahead);
    // Where its path first touched static geometry that the end would not answer (limb_contacts.hpp).
    const Eigen::Vector3d from = p.previous(ball.particle).template cast<double>(), path = segment.head - from;
    if (segment.reach > 0 && path.norm() > kSweptSlop * segment.radius) {
      const SweptTouch touch = state.collisions.first_static_touch(index, from, segment.head, segment.radius);
      if (touch.found()) segment.head = segment.tail = from + touch.time * path;
    }
  }
}

// A segment's end particles: a Model body's head and tail, or a ball's one particle twice.
template <typename Scalar>
std::pair<std::uint32_t, std::uint32_t> ends_of(const VerletState<Scalar>& state, std::uint32_t segment) {
  const std::size_t bodies = state.body_limb.size();
  if (segment >= bodies) {
    const std::uint32_t ball = state.balls[segment - bodies].particle;
    return {ball, ball};
  }
  const std::uint32_t limb = state.body_limb[segment];
  return {state.limbs.head[limb], state.limbs.tail[limb]};
}

// Places `place` and place + 1 of the row: the point `axial` of the way from head to tail,
// times `sign`; a ball's one particle takes one place (a particle twice in a row would lose
// one of its two moves when the sweep writes them back). A sphere limb's segment is its centre:
// its contacts act half way between its particles, whatever `axial` its point segment gave.
inline void set_places(ContactRow& row, std::size_t place, std::pair<std::uint32_t, std::uint32_t> ends, double axial, double sign) {
  const auto [head, tail] = ends;
  row.particle[place] = head, row.coefficient[place] = sign * (1 - axial);
  if (tail != head) row.particle[place + 1] = tail, row.coefficient[place + 1] = sign * axial;
  else row.coefficient[place] = sign;
}

template <typename Scalar>
void wake_island_of_segment(VerletState<Scalar>& state, std::uint32_t segment) {
  const std::size_t bodies = state.body_limb.size();
  if (segment >= bodies) {
    wake_island(state, state.balls[segment - bodies].island);
    return;
  }
  const std::uint32_t limb = state.body_limb[segment];
  for (std::uint32_t k = 0; k < state.islands.size(); ++k) {
    const Island& island = state.islands[k];
    if (limb >= island.limb_begin && limb < island.limb_end) {
      wake_island(state, k);
      return;
    }
  }
}

// n·Σ c_k x_k over the row's places, at the positions (or previous positions, or velocities) `get` gives.
template <typename Get>
double along_normal(const ContactRow& row, Get&& get) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < kContactRowParticles; ++k) {
    if (row.coefficient[k] != 0) sum += row.coefficient[k] * get(row.particle[k]);
  }
  return row.normal.dot(sum);
}

// Σ w_k c_k², the row's generalized inverse mass, 1/kg.
template <typename Scalar>
double row_inverse_mass(const VerletState<Scalar>& state, const ContactRow& row) {
  double sum = 0;
  for (std::size_t k = 0; k < kContactRowParticles; ++k) {
    sum += double(state.particles.inverse_mass[row.particle[k]]) * row.coefficient[k] * row.coefficient[k];
  }
  return sum;
}

// The row of one contact, its offset moved by the overlap it may keep this substep.
template <typename Scalar>
ContactRow contact_row(const VerletState<Scalar>& state, const LimbContact& contact, double dt) {
  ContactRow row;
  const std::uint32_t null_particle = state.particles.null_particle();
  row.particle.fill(null_particle);
  const auto axial = [&](std::uint32_t segment, double along) {
    return segment < state.body_limb.size() && state.limbs.sphere[state.body_limb[segment]] ? 0.5 : along;
  };
  set_places(row, 0, ends_of(state, contact.first), axial(contact.first, contact.axial_first), 1);
  double offset = contact.offset;
  if (contact.second != kStaticShape) {
    set_places(row, 2, ends_of(state, contact.second), axial(contact.second, contact.axial_second), -1);
    offset = state.limb_segments[contact.first].radius + state.limb_segments[contact.second].radius;
  }
  row.normal = contact.normal;
  row.friction = contact.friction;
  row.restitution = contact.restitution;
  const auto& particles = state.particles;
  const double start_separation =
      along_normal(row, [&](std::uint32_t p) -> Eigen::Vector3d { return particles.previous(p).template cast<double>(); }) - offset;
  row.offset = offset + allowed_separation(start_separation, state.settings.contact_recovery_speed * dt);
  row.approach_speed = along_normal(row, [&](std::uint32_t p) { return contact_velocity(state, p, dt); });
  return row;
}

}  // namespace

template <typename Scalar>
bool detect_limb_contacts(VerletState<Scalar>& state, double dt, int substeps_ahead, bool reuse_pairs) {
  state.contact_rows.rows.clear();
  if (!state.collisions.active() || state.awake_islands.empty()) return false;
  // The last search's pairs serve while no island woke or fell asleep since and no segment
  // outran its search reach.
  gather_segments(state, std::max(1, substeps_ahead));
  // The narrowphase on the relaxation's threads (the same contacts on any number).
  BlockRunner* runner = state.plan.runner.operator->();
  const bool kept = reuse_pairs && state.pairs_searched_for == state.awake_generation &&
                    state.collisions.find_kept_pairs(state.limb_segments, state.limb_awake, kMarginSlop, state.limb_contacts, runner);
  if (!kept) state.collisions.find(state.limb_segments, state.limb_awake, kMarginSlop, state.limb_contacts, runner);
  // A wake below makes the next substep search again (a woken limb's pairs with sleeping ones).
  state.pairs_searched_for = substeps_ahead > 1 || kept ? state.awake_generation : ~std::uint64_t{0};
  for (const LimbContact& contact : state.limb_contacts) {
    // An awake limb or ball reaching a sleeping one wakes it (its rows join the next sweep's batches).
    for (std::uint32_t segment : {contact.first, contact.second}) {
      if (segment != kStaticShape && !state.limb_awake[segment] && contact.separation < kMarginSlop) wake_island_of_segment(state, segment);
    }
    state.contact_rows.rows.push_back(contact_row(state, contact, dt));
  }
  return !kept;
}

template <typename Scalar>
double apply_contact_row_restitution(VerletState<Scalar>& state, double dt) {
  const ContactRowBatches<Scalar>& batches = state.plan.contact_batches;
  const double resting = resting_speed(state, dt);
  auto& particles = state.particles;
  double largest = 0;
  for (std::size_t slot = 0; slot < batches.slot_count(); ++slot) {
    if (batches.row[slot] == ~std::uint32_t{0}) continue;
    ContactRow& row = state.contact_rows.rows[batches.row[slot]];
    const double separation =
        along_normal(row, [&](std::uint32_t p) -> Eigen::Vector3d { return particles.position(p).template cast<double>(); }) - row.offset;
    const double inverse_mass = row_inverse_mass(state, row);
    if (separation > kTouchingSlop || inverse_mass <= 0) continue;
    const double target = bounce_speed(row.approach_speed, row.restitution, resting);
    const double speed = along_normal(row, [&](std::uint32_t p) { return contact_velocity(state, p, dt); });
    // A row relaxation did not push keeps a separating speed of its own (contact_impulse's clamp
    // says the same under rattle).
    if (!uses_rattle(state) && speed >= target && batches.lambda[slot] <= 0) continue;
    const double wanted = (target - speed) / inverse_mass;  // N·s, thesis eq. 2.33
    const double impulse = contact_impulse(state, wanted, double(batches.lambda[slot]), dt, row.velocity_impulse);
    if (impulse == 0) continue;
    for (std::size_t k = 0; k < kContactRowParticles; ++k) {
      const std::uint32_t p = row.particle[k];
      const double share = double(particles.inverse_mass[p]) * row.coefficient[k];
      if (share == 0) continue;
      change_velocity(state, p, share * impulse * row.normal, dt);
    }
    largest = std::max(largest, std::abs(impulse) * inverse_mass);
  }
  return largest;
}

#define LIMBER_INSTANTIATE(Scalar)                                                  \
  template bool detect_limb_contacts<Scalar>(VerletState<Scalar>&, double, int, bool); \
  template double apply_contact_row_restitution<Scalar>(VerletState<Scalar>&, double);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
