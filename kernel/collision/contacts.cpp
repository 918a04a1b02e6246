#include "limber/kernel/collision/contacts.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"

namespace limber {
namespace {

template <typename Scalar>
Eigen::Vector3d position_of(const ParticleBuffer<Scalar>& particles, std::uint32_t p, bool previous = false) {
  return (previous ? particles.previous(p) : particles.position(p)).template cast<double>();
}
// Every particle at x* + t·(x − x*): t = 0 the previous positions, t = 1 the current ones.
template <typename Scalar>
Eigen::Vector3d position_at(const ParticleBuffer<Scalar>& particles, std::uint32_t p, double t) {
  return (1 - t) * position_of(particles, p, true) + t * position_of(particles, p);
}
template <typename Scalar>
void move(ParticleBuffer<Scalar>& particles, std::uint32_t p, const Eigen::Vector3d& delta) {
  particles.set_position(p, particles.position(p) + delta.cast<Scalar>());
}
// --- Plane contacts ---

// A feature against a plane, at the current or the previous positions.
template <typename Scalar>
PlaneFeatureConstraint plane_constraint(const VerletState<Scalar>& state, std::uint32_t f, std::uint32_t plane_index,
                                        bool previous = false) {
  const ContactFeature& feature = state.features[f];
  const Plane& plane = state.planes[plane_index];
  return plane_feature_constraint(plane.normal, plane.offset, position_of(state.particles, feature.particle, previous),
                                  position_of(state.particles, feature.axis_partner, previous), feature.radius,
                                  feature.is_disk, feature.at_centre);
}

// Generalized inverse mass Σ w |∇C|² of a plane contact (a sphere: the particle's own w).
template <typename Scalar>
double plane_inverse_mass(const VerletState<Scalar>& state, const ContactFeature& feature,
                          const PlaneFeatureConstraint& constraint) {
  const auto& w = state.particles.inverse_mass;
  double sum = w[feature.particle] * constraint.gradient_point.squaredNorm();
  if (feature.axis_partner != feature.particle) sum += w[feature.axis_partner] * constraint.gradient_partner.squaredNorm();
  return sum;
}

// Rate of change of C, ∇C·v, m/s.
template <typename Scalar>
double plane_normal_speed(const VerletState<Scalar>& state, const ContactFeature& feature,
                          const PlaneFeatureConstraint& constraint, double dt) {
  double speed = constraint.gradient_point.dot(contact_velocity(state, feature.particle, dt));
  if (feature.axis_partner != feature.particle) {
    speed += constraint.gradient_partner.dot(contact_velocity(state, feature.axis_partner, dt));
  }
  return speed;
}

// --- Ball–limb contacts ---

// A sphere limb meets the ball at its centre: half way between its particles (axial ½).
template <typename Scalar>
SphereLimbContact ball_limb_geometry(const VerletState<Scalar>& state, const BallParticle& ball, std::uint32_t limb, double t) {
  const auto& particles = state.particles;
  Eigen::Vector3d head = position_at(particles, state.limbs.head[limb], t), tail = position_at(particles, state.limbs.tail[limb], t);
  if (state.limbs.sphere[limb]) head = tail = 0.5 * (head + tail);
  SphereLimbContact contact = sphere_limb_contact(position_at(particles, ball.particle, t), ball.radius, head, tail,
                                                  state.limbs.shape[limb], state.limbs.radius[limb]);
  if (state.limbs.sphere[limb]) contact.axial = 0.5;
  return contact;
}

// From the limb's contact point to the ball's centre, at time t of the step.
template <typename Scalar>
Eigen::Vector3d ball_from_limb_point(const VerletState<Scalar>& state, const BallParticle& ball, std::uint32_t limb, double axial,
                                     double t = 1) {
  const auto& particles = state.particles;
  return position_at(particles, ball.particle, t) -
         (1 - axial) * position_at(particles, state.limbs.head[limb], t) -
         axial * position_at(particles, state.limbs.tail[limb], t);
}

template <typename Scalar>
double ball_separation(const VerletState<Scalar>& state, const BallContact& contact) {
  return contact.normal.dot(ball_from_limb_point(state, state.balls[contact.ball], contact.limb, contact.axial)) - contact.offset;
}

// Relative normal velocity of the ball against the contact's limb point, m/s.
template <typename Scalar>
double ball_normal_speed(const VerletState<Scalar>& state, const BallContact& contact, double dt) {
  const Eigen::Vector3d limb_velocity = (1 - contact.axial) * contact_velocity(state, state.limbs.head[contact.limb], dt) +
                                        contact.axial * contact_velocity(state, state.limbs.tail[contact.limb], dt);
  return contact.normal.dot(contact_velocity(state, state.balls[contact.ball].particle, dt) - limb_velocity);
}

// Generalized inverse mass of a ball–limb contact (the denominator of thesis eq. 2.33 for a
// point a of the way from the limb's head to its tail).
template <typename Scalar>
double ball_limb_inverse_mass(const VerletState<Scalar>& state, const BallContact& contact) {
  const auto& w = state.particles.inverse_mass;
  const double a = contact.axial;
  return w[state.balls[contact.ball].particle] + (1 - a) * (1 - a) * w[state.limbs.head[contact.limb]] +
         a * a * w[state.limbs.tail[contact.limb]];
}

// Shares a position (kg·m) or velocity (N·s) impulse along the contact normal between the ball
// (+) and the limb's particles (−), each in proportion to its inverse mass and lever.
template <typename Scalar, typename Apply>
void share_ball_limb_impulse(const VerletState<Scalar>& state, const BallContact& contact, const Eigen::Vector3d& impulse,
                             Apply&& apply) {
  const auto& w = state.particles.inverse_mass;
  const std::uint32_t ball = state.balls[contact.ball].particle;
  const std::uint32_t head = state.limbs.head[contact.limb], tail = state.limbs.tail[contact.limb];
  const double a = contact.axial;
  apply(ball, Eigen::Vector3d(w[ball] * impulse));
  apply(head, Eigen::Vector3d(-(1 - a) * w[head] * impulse));
  apply(tail, Eigen::Vector3d(-a * w[tail] * impulse));
}

// --- The velocity pass on limbs with a centre particle ---

// How a limb with a centre particle (LimbMasses::inertia) answers a velocity impulse λ that
// reaches it through its end particles, as the gradients g_head, g_tail of a contact's
// constraint. Given to the ends alone (Δv = w·λ·g, as for two-particle limbs) it would move only
// their mass — a third of a uniform rod's — and the centre's constraints would take most of it
// back the next step: a rod dropped flat with restitution 0.5 bounced with 0.05. So the limb
// answers as the rigid body its three particles make, which is what a two-particle limb does
// for impulses across its axis. With masses m_p = 1/w_p at x_p, centre of mass X, r_p = x_p − X,
// axis u, transverse second moment S = Σ m_p (r_p·u)², g = g_head + g_tail and torque
// τ = r_head × g_head + r_tail × g_tail, whose part τ⊥ across the axis is all that particles on
// the axis can take:
//   Δv_p = λ·(g/M + (τ⊥/S) × r_p),   generalized inverse mass K = |g|²/M + |τ⊥|²/S.
// A limb held by one pinned particle q (w_q = 0) turns about it (r_p = x_p − x_q, no g/M term);
// held by two it does not move (K = 0). Joints are not seen, as for two-particle limbs.
struct RigidLimbResponse {
  std::array<std::uint32_t, 3> particles{};  // head, centre, tail
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();   // g/M, 1/kg
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();  // τ⊥/S, 1/(kg·m)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();   // X, or the pinned particle, m
  double inverse_mass = 0;                            // K, 1/kg
};

template <typename Scalar>
bool has_centre(const VerletState<Scalar>& state, std::uint32_t limb) {
  return limb != kNoLimb && state.limbs.centre[limb] != kNoCentre;
}

template <typename Scalar>
RigidLimbResponse rigid_limb_response(const VerletState<Scalar>& state, std::uint32_t limb,
                                      const Eigen::Vector3d& gradient_head, const Eigen::Vector3d& gradient_tail) {
  const auto& w = state.particles.inverse_mass;
  RigidLimbResponse response;
  response.particles = {state.limbs.head[limb], state.limbs.centre[limb], state.limbs.tail[limb]};
  std::array<Eigen::Vector3d, 3> x;
  int pinned_count = 0, pinned = 0;
  double mass = 0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    x[k] = position_of(state.particles, response.particles[k]);
    if (w[response.particles[k]] == 0) {
      ++pinned_count, pinned = k;
    } else {
      mass += 1 / double(w[response.particles[k]]);
      moment += x[k] / double(w[response.particles[k]]);
    }
  }
  if (pinned_count > 1) return response;
  response.origin = pinned_count == 0 ? Eigen::Vector3d(moment / mass) : x[pinned];
  const Eigen::Vector3d axis = (x[0] - x[2]).normalized();
  double second_moment = 0;
  for (int k = 0; k < 3; ++k) {
    if (w[response.particles[k]] == 0) continue;
    const double along = (x[k] - response.origin).dot(axis);
    second_moment += along * along / double(w[response.particles[k]]);
  }
  const Eigen::Vector3d torque =
      (x[0] - response.origin).cross(gradient_head) + (x[2] - response.origin).cross(gradient_tail);
  const Eigen::Vector3d torque_across = torque - torque.dot(axis) * axis;
  if (second_moment > 0) response.angular = torque_across / second_moment;
  if (pinned_count == 0) response.linear = (gradient_head + gradient_tail) / mass;
  response.inverse_mass = (gradient_head + gradient_tail).dot(response.linear) + torque_across.dot(response.angular);
  return response;
}

// Changes the limb's particle velocities by the response to the impulse λ (N·s).
template <typename Scalar>
void apply_rigid_limb_impulse(VerletState<Scalar>& state, const RigidLimbResponse& response, double impulse, double dt) {
  for (const std::uint32_t p : response.particles) {
    const Eigen::Vector3d r = position_of(state.particles, p) - response.origin;
    change_velocity(state, p, impulse * (response.linear + response.angular.cross(r)), dt);
  }
}

// Finds the ball's contact with a limb during the step. A fast ball can cross most of a thin
// limb in one step, and the overlap at the end of the step then points sideways (it would wedge
// the legs apart instead of striking them); so the contact plane is fixed where the surfaces
// first met — the time of impact, by bisection on the separation of the interpolated
// configuration, as continuous collision detection does. A contact already overlapping at the
// start of the step keeps that configuration's plane.
template <typename Scalar>
bool find_ball_contact(const VerletState<Scalar>& state, const BallParticle& ball, std::uint32_t limb, BallContact& contact) {
  // A limb (or ball) gone non-finite touches nothing: its contact would carry the NaN to the ball
  // and from it to every body the ball meets.
  if (!std::isfinite(ball_limb_geometry(state, ball, limb, 1.0).separation)) return false;
  const SphereLimbContact start = ball_limb_geometry(state, ball, limb, 0.0);
  if (!std::isfinite(start.separation)) return false;
  double time = 0;
  if (start.separation >= 0) {
    // Samples close enough that the ball cannot cross the limb between two: the relative motion
    // between samples stays below the thinner of the two diameters' halves (a 100 m/s ball at
    // 1/60 s against a 4 cm limb: about 80 samples; a resting contact: 4).
    const auto& particles = state.particles;
    const auto moved = [&](std::uint32_t p) { return (position_at(particles, p, 1) - position_at(particles, p, 0)).norm(); };
    const double motion = moved(ball.particle) + std::max(moved(state.limbs.head[limb]), moved(state.limbs.tail[limb]));
    const double spacing = 0.5 * std::max(std::min(ball.radius, state.limbs.radius[limb]), 1e-4);
    const int samples = static_cast<int>(std::clamp(std::ceil(motion / spacing), 4.0, 1024.0));
    double inside = -1;  // the first sampled time with overlap
    for (int k = 1; k <= samples; ++k) {
      if (ball_limb_geometry(state, ball, limb, double(k) / samples).separation < 0) {
        inside = double(k) / samples;
        break;
      }
    }
    if (inside < 0) return false;
    double outside = inside - 1.0 / samples;
    for (int k = 0; k < 24; ++k) {
      const double middle = 0.5 * (outside + inside);
      (ball_limb_geometry(state, ball, limb, middle).separation < 0 ? inside : outside) = middle;
    }
    time = outside;
  }
  const SphereLimbContact touch = ball_limb_geometry(state, ball, limb, time);
  contact.limb = limb;
  contact.normal = touch.normal;
  contact.axial = touch.axial;
  // The plane passes through the surfaces as they were at that time: C(time) = separation(time).
  contact.offset = touch.normal.dot(ball_from_limb_point(state, ball, limb, touch.axial, time)) - touch.separation;
  contact.start_separation = start.separation;
  return true;
}

}  // namespace

template <typename Scalar>
void detect_ball_contacts(VerletState<Scalar>& state, double dt) {
  state.ball_contacts.clear();
  const auto awake = [&](const BallParticle& ball) { return !state.islands[ball.island].sleeping; };
  if (std::none_of(state.balls.begin(), state.balls.end(), awake)) return;
  // Candidates through the broadphase (BallCandidates): each limb's bounding sphere now and each
  // ball's path this step grown by its radius, as boxes — what the sphere test below can accept
  // (none to fill for a few balls: each then tests every limb).
  BallCandidates& candidates = state.collisions.ball_candidates();
  const std::span<Aabb> boxes = candidates.boxes(state.limbs.size(), state.balls.size());
  for (std::uint32_t limb = 0; limb < state.limbs.size() && !boxes.empty(); ++limb) {
    const Eigen::Vector3d head = position_of(state.particles, state.limbs.head[limb]);
    const Eigen::Vector3d tail = position_of(state.particles, state.limbs.tail[limb]);
    const double reach = 0.5 * (tail - head).norm() + state.limbs.radius[limb];
    boxes[limb] = {(0.5 * (head + tail)).array() - reach, (0.5 * (head + tail)).array() + reach};
  }
  for (std::uint32_t b = 0; b < state.balls.size() && !boxes.empty(); ++b) {
    const BallParticle& ball = state.balls[b];
    const Eigen::Vector3d from = position_of(state.particles, ball.particle, true), to = position_of(state.particles, ball.particle);
    boxes[state.limbs.size() + b] = {from.cwiseMin(to).array() - ball.radius, from.cwiseMax(to).array() + ball.radius};
  }
  candidates.find(/*other_balls=*/false);
  for (std::uint32_t b = 0; b < state.balls.size(); ++b) {
    const BallParticle& ball = state.balls[b];
    if (!awake(ball)) continue;
    const Eigen::Vector3d from = position_of(state.particles, ball.particle, true), to = position_of(state.particles, ball.particle);
    const Eigen::Vector3d path = to - from;
    for (const std::uint32_t limb : candidates.of(b)) {
      // Bounding spheres first (thesis 2.4), the limb's against the ball's path this step; the
      // exact test only when they overlap.
      const Eigen::Vector3d head = position_of(state.particles, state.limbs.head[limb]);
      const Eigen::Vector3d tail = position_of(state.particles, state.limbs.tail[limb]);
      const Eigen::Vector3d centre = 0.5 * (head + tail);
      const double reach = 0.5 * (tail - head).norm() + state.limbs.radius[limb] + ball.radius;
      const double along =
          path.squaredNorm() > 0 ? std::clamp((centre - from).dot(path) / path.squaredNorm(), 0.0, 1.0) : 0.0;
      if ((centre - (from + along * path)).squaredNorm() > reach * reach) continue;
      BallContact contact;
      if (!find_ball_contact(state, ball, limb, contact)) continue;
      // The limb's island: islands hold consecutive limbs, in order.
      const auto island = std::upper_bound(state.islands.begin(), state.islands.end(), limb,
                                           [](std::uint32_t l, const Island& i) { return l < i.limb_end; });
      wake_island(state, static_cast<std::uint32_t>(island - state.islands.begin()));
      contact.ball = b;
      contact.approach_speed = ball_normal_speed(state, contact, dt);
      state.ball_contacts.push_back(contact);
    }
  }
}

template <typename Scalar>
void detect_plane_contacts(VerletState<Scalar>& state, double dt) {
  state.plane_contacts.clear();
  for (std::uint32_t k : state.awake_islands) {
    const Island& island = state.islands[k];
    for (std::uint32_t f = island.feature_begin; f < island.feature_end; ++f) {
      for (std::uint32_t plane = 0; plane < state.planes.size(); ++plane) {
        const PlaneFeatureConstraint constraint = plane_constraint(state, f, plane);
        if (constraint.separation >= 0) continue;
        PlaneContact contact;
        contact.feature = f, contact.plane = plane;
        contact.approach_speed = plane_normal_speed(state, state.features[f], constraint, dt);
        contact.start_separation = plane_constraint(state, f, plane, /*previous=*/true).separation;
        state.plane_contacts.push_back(contact);
      }
    }
  }
}

template <typename Scalar>
double project_plane_contacts(VerletState<Scalar>& state, double dt) {
  const double recovery = state.settings.contact_recovery_speed * dt;
  auto& particles = state.particles;
  double largest = 0;
  for (PlaneContact& contact : state.plane_contacts) {
    if (contact.held_by_trees) continue;  // tree_contacts.hpp
    const ContactFeature& feature = state.features[contact.feature];
    const PlaneFeatureConstraint constraint = plane_constraint(state, contact.feature, contact.plane);
    const double push = allowed_separation(contact.start_separation, recovery) - constraint.separation;
    const double inverse_mass = plane_inverse_mass(state, feature, constraint);
    if (push <= 0 || inverse_mass <= 0) continue;
    // λ = −C / Σ w|∇C|²; each particle moves w·λ·∇C (for a sphere: the whole push along n).
    const double lambda = push / inverse_mass;
    contact.position_impulse += lambda;
    const std::uint32_t p = feature.particle, q = feature.axis_partner;
    Eigen::Vector3d delta = particles.inverse_mass[p] * lambda * constraint.gradient_point;
    Eigen::Vector3d delta_partner = particles.inverse_mass[q] * lambda * constraint.gradient_partner;
    // Coulomb friction on the particle's tangential displacement this step (a sphere limb's: its
    // centre's, taken from both), at most μ times the push.
    const Plane& plane = state.planes[contact.plane];
    if (particles.inverse_mass[p] > 0) {
      const auto step_of = [&](std::uint32_t k) -> Eigen::Vector3d { return (particles.position(k) - particles.previous(k)).template cast<double>(); };
      const Eigen::Vector3d step = feature.at_centre ? Eigen::Vector3d(0.5 * (step_of(p) + step_of(q))) : step_of(p);
      const Eigen::Vector3d tangential = step - step.dot(plane.normal) * plane.normal;
      const double slide = tangential.norm(), grip = plane.friction * push;
      const Eigen::Vector3d held = slide > 0 ? Eigen::Vector3d((slide <= grip ? 1.0 : grip / slide) * tangential) : Eigen::Vector3d::Zero();
      delta -= held;
      if (feature.at_centre) delta_partner -= held;
    }
    if (q != p) {
      move(particles, q, delta_partner);
      largest = std::max(largest, delta_partner.norm());
    }
    move(particles, p, delta);
    largest = std::max(largest, delta.norm());
  }
  state.counters.contact_projections += state.plane_contacts.size();
  return largest;
}

template <typename Scalar>
double project_ball_contacts(VerletState<Scalar>& state, double dt) {
  const double recovery = state.settings.contact_recovery_speed * dt;
  double largest = 0;
  for (BallContact& contact : state.ball_contacts) {
    const double error = ball_separation(state, contact) - allowed_separation(contact.start_separation, recovery);
    const double inverse_mass = ball_limb_inverse_mass(state, contact);
    if (error >= 0 || inverse_mass <= 0) continue;
    contact.position_impulse += -error / inverse_mass;
    const Eigen::Vector3d impulse = (-error / inverse_mass) * contact.normal;  // kg·m
    share_ball_limb_impulse(state, contact, impulse, [&](std::uint32_t p, const Eigen::Vector3d& d) {
      move(state.particles, p, d);
      largest = std::max(largest, d.norm());
    });
  }
  state.counters.contact_projections += state.ball_contacts.size();
  return largest;
}

namespace {

// One pass of the restitution impulses over every contact of the step. Returns the largest
// change of a contact's normal speed, m/s.
template <typename Scalar>
double restitution_pass(VerletState<Scalar>& state, double dt) {
  const double resting = resting_speed(state, dt);
  auto& particles = state.particles;
  double largest = 0;
  for (PlaneContact& contact : state.plane_contacts) {
    if (contact.held_by_trees) continue;  // tree_contacts.hpp: no bounce
    const ContactFeature& feature = state.features[contact.feature];
    const PlaneFeatureConstraint constraint = plane_constraint(state, contact.feature, contact.plane);
    const double restitution = std::max(state.planes[contact.plane].restitution, feature.restitution);
    const double target = bounce_speed(contact.approach_speed, restitution, resting);
    if (has_centre(state, feature.limb)) {
      if (constraint.separation > kTouchingSlop) continue;
      const bool at_head = feature.particle == state.limbs.head[feature.limb];
      const Eigen::Vector3d partner =
          feature.axis_partner != feature.particle ? constraint.gradient_partner : Eigen::Vector3d::Zero();
      const RigidLimbResponse response = rigid_limb_response(state, feature.limb, at_head ? constraint.gradient_point : partner,
                                                             at_head ? partner : constraint.gradient_point);
      if (response.inverse_mass <= 0) continue;
      const double wanted = (target - plane_normal_speed(state, feature, constraint, dt)) / response.inverse_mass;
      const double impulse = contact_impulse(state, wanted, contact.position_impulse, dt, contact.velocity_impulse);
      apply_rigid_limb_impulse(state, response, impulse, dt);
      largest = std::max(largest, std::abs(impulse) * response.inverse_mass);
      continue;
    }
    const double inverse_mass = plane_inverse_mass(state, feature, constraint);
    if (constraint.separation > kTouchingSlop || inverse_mass <= 0) continue;  // lifted off, or fixed
    const double wanted = (target - plane_normal_speed(state, feature, constraint, dt)) / inverse_mass;
    const double impulse = contact_impulse(state, wanted, contact.position_impulse, dt, contact.velocity_impulse);  // N·s
    change_velocity(state, feature.particle,
                    particles.inverse_mass[feature.particle] * impulse * constraint.gradient_point, dt);
    if (feature.axis_partner != feature.particle) {
      change_velocity(state, feature.axis_partner,
                      particles.inverse_mass[feature.axis_partner] * impulse * constraint.gradient_partner, dt);
    }
    largest = std::max(largest, std::abs(impulse) * inverse_mass);
  }
  for (BallContact& contact : state.ball_contacts) {
    const double target = bounce_speed(contact.approach_speed, state.balls[contact.ball].restitution, resting);
    const double normal_speed = ball_normal_speed(state, contact, dt);
    if (has_centre(state, contact.limb)) {
      if (ball_separation(state, contact) > kTouchingSlop) continue;
      const std::uint32_t ball = state.balls[contact.ball].particle;
      const RigidLimbResponse response = rigid_limb_response(state, contact.limb, -(1 - contact.axial) * contact.normal,
                                                             -contact.axial * contact.normal);
      const double inverse_mass = state.particles.inverse_mass[ball] + response.inverse_mass;
      if (inverse_mass <= 0) continue;
      const double wanted = (target - normal_speed) / inverse_mass;  // N·s, thesis eq. 2.33
      const double impulse = contact_impulse(state, wanted, contact.position_impulse, dt, contact.velocity_impulse);
      change_velocity(state, ball, state.particles.inverse_mass[ball] * impulse * contact.normal, dt);
      apply_rigid_limb_impulse(state, response, impulse, dt);
      largest = std::max(largest, std::abs(impulse) * inverse_mass);
      continue;
    }
    const double inverse_mass = ball_limb_inverse_mass(state, contact);
    if (ball_separation(state, contact) > kTouchingSlop || inverse_mass <= 0) continue;
    // Thesis eq. 2.33: J = Δv_n / (Σ generalized inverse masses), shared like the projection.
    const double wanted = (target - normal_speed) / inverse_mass;
    const double impulse = contact_impulse(state, wanted, contact.position_impulse, dt, contact.velocity_impulse);  // N·s
    share_ball_limb_impulse(state, contact, impulse * contact.normal,
                            [&](std::uint32_t p, const Eigen::Vector3d& dv) { change_velocity(state, p, dv, dt); });
    largest = std::max(largest, std::abs(impulse) * inverse_mass);
  }
  return largest;
}

// Contacts on two-particle limbs meet their target speeds in one pass: an impulse across the
// axis at one end leaves the other end's velocity alone. A rigid three-particle limb couples
// them — the impulse at its head turns it and drives its tail the other way — so the pass is
// repeated, Gauss-Seidel on the contacts' normal speeds: a uniform rod on its two ends loses 3/4
// of the error a pass (the coupling −2/m over the diagonal 4/m, squared), about 1e-5 after 8.
constexpr int kRigidLimbRestitutionPasses = 8;

}  // namespace

template <typename Scalar>
double apply_restitution(VerletState<Scalar>& state, double dt) {
  const bool centres = state.limbs.size() > 0 && state.limbs.centre[0] != kNoCentre;
  const int passes = centres ? kRigidLimbRestitutionPasses : 1;
  double largest = 0;
  for (int pass = 0; pass < passes; ++pass) largest = std::max(largest, restitution_pass(state, dt));
  return largest;
}

#define LIMBER_INSTANTIATE(Scalar)                                                \
  template void detect_ball_contacts<Scalar>(VerletState<Scalar>&, double);      \
  template void detect_plane_contacts<Scalar>(VerletState<Scalar>&, double);     \
  template double project_plane_contacts<Scalar>(VerletState<Scalar>&, double);  \
  template double project_ball_contacts<Scalar>(VerletState<Scalar>&, double);   \
  template double apply_restitution<Scalar>(VerletState<Scalar>&, double);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
