#include "limber/kernel/lagrange/contacts.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/lagrange/multipliers.hpp"
#include "limber/kernel/numerics/contact_projection.hpp"

namespace limber {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Row = JointContactScratch::Row;
using Kind = JointContactScratch::Kind;

// Projected Gauss-Seidel sweeps over the rows. The responses are exact, so the sweeps only
// resolve the coupling between rows (a welded foot's two capsules, both feet through the legs,
// a limit and a contact). On humanoid.xml's landing (bench/mjcf_landing, 2 s at 5 ms) 6, 12, 24
// and 48 sweeps leave the deepest penetration at 2.6, 1.1, 0.21 and 0.19 mm and the largest
// limit violation at 1.8·10⁻³, 1.8·10⁻³, 3.3·10⁻⁴ and 2.9·10⁻⁵ rad; the joint gap (1.3–1.4 mm)
// is the step's, whatever the count.
constexpr int kSweeps = 24;

// Whether row r is a contact's normal followed by its two tangents (the contact has friction).
bool with_tangents(const JointContactScratch& s, std::size_t r) {
  return s.rows[r].kind == Kind::normal && r + 2 < s.rows.size() && s.rows[r + 1].kind == Kind::tangent;
}

// G_r·x over the row's two bodies (x: one 6-vector per body).
double row_rate(const Row& row, const Vector6* x) {
  double rate = row.jacobian_a.dot(x[row.a]);
  if (row.b >= 0) rate += row.jacobian_b.dot(x[row.b]);
  return rate;
}
double row_rate(const Row& row, const std::vector<Vector6>& x) { return row_rate(row, x.data()); }

// The response of the row's batch, per body (of n).
const Vector6* response_of(const JointContactScratch& s, const Row& row, std::size_t n) { return s.responses.data() + row.batch * n; }

// Puts the row in the first batch whose solve none of its islands has used yet.
void add_row(const LagrangeState& state, JointContactScratch& s, Row row) {
  const std::uint32_t ca = state.island_of_body[row.a], cb = row.b >= 0 ? state.island_of_body[row.b] : ca;
  row.batch = std::max(s.next_batch[ca], s.next_batch[cb]);
  s.next_batch[ca] = s.next_batch[cb] = row.batch + 1;
  s.rows.push_back(row);
}

// Rows for every contact (its normal, and the two tangents when it has friction: [d; (p − c) × d]
// on a, the negative on b) and every limit's nearer side (the control row's Jacobian, signed so
// that G·x ≥ target keeps it inside).
void build_rows(LagrangeState& state, JointContactScratch& s, double dt) {
  s.rows.clear();
  std::fill(s.next_batch.begin(), s.next_batch.end(), 0u);
  const RigidBodyState& y = state.bodies.state;
  for (std::size_t k = 0; k < state.contacts.size(); ++k) {
    RigidContact& contact = state.contacts[k];
    const Eigen::Vector3d& n = contact.normal;
    const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    const std::size_t first = s.rows.size();
    for (int d = 0; d < (contact.friction > 0 ? 3 : 1); ++d) {
      const Eigen::Vector3d direction = d == 0 ? n : d == 1 ? t1 : t2;
      Row row;
      row.kind = d == 0 ? Kind::normal : Kind::tangent;
      row.contact = static_cast<std::uint32_t>(k);
      row.a = contact.a, row.b = contact.b;
      row.jacobian_a.head<3>() = direction;
      row.jacobian_a.tail<3>() = (contact.point - y.position[row.a]).cross(direction);
      if (row.b >= 0) {
        row.jacobian_b.head<3>() = -direction;
        row.jacobian_b.tail<3>() = (y.position[row.b] - contact.point).cross(direction);
      }
      add_row(state, s, row);
    }
    // The approach before any impulse decides bouncing and bounds the push-out.
    record_approach(contact, -row_rate(s.rows[first], s.velocity), state.settings, dt);
  }
  for (const ControlledJoint& joint : state.controls.joints) {
    const std::int32_t inboard = state.constraints.inboard[joint.joint], outboard = state.constraints.outboard[joint.joint];
    for (std::uint32_t r = joint.first_row; r < joint.first_row + joint.count; ++r) {
      const ControlRow& control = state.controls.rows[r];
      if (control.side == 0) continue;
      Row row;
      row.kind = Kind::limit;
      row.a = outboard, row.b = inboard;
      const double side = control.side;
      row.jacobian_a = side * control.outboard_jacobian.transpose();
      if (inboard >= 0) row.jacobian_b = side * control.inboard_jacobian.transpose();
      row.gap = control.gap;
      add_row(state, s, row);
    }
  }
}

// One solve against the joints' factor per batch: the responses of its rows, each on its own
// islands' bodies.
void measure_responses(LagrangeState& state, JointContactScratch& s) {
  const std::size_t n = state.bodies.size();
  std::uint32_t batches = 0;
  for (const Row& row : s.rows) batches = std::max(batches, row.batch + 1);
  // Each batch's right-hand side (its rows' G_rᵀ) first, in one pass over the rows; each solve
  // then replaces its batch's with the responses.
  s.responses.assign(batches * n, Vector6::Zero());  // within what compile reserved, unless the contacts grew past it
  for (const Row& row : s.rows) {
    Vector6* rhs = s.responses.data() + row.batch * n;
    rhs[row.a] += row.jacobian_a;
    if (row.b >= 0) rhs[row.b] += row.jacobian_b;
  }
  for (auto& rhs : state.constraint_rhs) rhs.setZero();
  const RigidBodyState& y = state.bodies.state;
  factor_constrained(state);
  for (std::uint32_t batch = 0; batch < batches; ++batch) {
    const auto first = s.responses.begin() + static_cast<std::ptrdiff_t>(batch * n);
    std::copy(first, first + static_cast<std::ptrdiff_t>(n), state.body_rhs.begin());
    solve_factored(state, y, state.body_rhs, state.constraint_rhs, state.accelerations);
    std::copy(state.accelerations.begin(), state.accelerations.end(), first);
  }
  for (Row& row : s.rows) row.mobility = row_rate(row, response_of(s, row, n));  // W_rr
  // Each contact's 3×3 block of W over its normal and tangents: its rows' rates per unit impulse
  // on each other (their responses are their batches', on their own islands' bodies).
  for (std::size_t r = 0; r + 2 < s.rows.size(); ++r) {
    if (!with_tangents(s, r)) continue;
    Row& normal = s.rows[r];
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j) normal.contact_block(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = row_rate(s.rows[r + i], response_of(s, s.rows[r + j], n));
    }
    normal.contact_block = 0.5 * (normal.contact_block + normal.contact_block.transpose()).eval();  // symmetric in exact arithmetic
  }
}

// Adds amount × the row's response to x, on the bodies of the row's islands.
void add_response(const LagrangeState& state, const JointContactScratch& s, const Row& row, double amount, std::vector<Vector6>& x) {
  const Vector6* response = response_of(s, row, x.size());
  const std::uint32_t ca = state.island_of_body[row.a], cb = row.b >= 0 ? state.island_of_body[row.b] : ca;
  for (const std::uint32_t c : {ca, cb}) {
    for (const std::uint32_t b : state.islands[c].bodies) x[b] += amount * response[b];
    if (cb == ca) break;
  }
}

// Projected Gauss-Seidel on G·x ≥ target, λ ≥ 0 for the unilateral rows; a contact with friction
// takes its three rows together, Coulomb's disc |λ_t| ≤ μ·λ_n held by the step of
// project_contact_impulse (kernel/numerics/contact_projection.hpp: the one Featherstone's contacts
// take) on its block of W. x holds the bodies' motion and moves with every change of λ.
// `with_friction` false leaves the tangent rows out. `warm`: the rows start from their impulses
// (applied to x first), else from none.
void project_rows(const LagrangeState& state, JointContactScratch& s, std::vector<Vector6>& x, bool with_friction, bool warm) {
  for (Row& row : s.rows) {
    if (!warm) row.impulse = 0;
    if (row.impulse != 0) add_response(state, s, row, row.impulse, x);
  }
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    for (std::size_t r = 0; r < s.rows.size(); ++r) {
      Row& row = s.rows[r];
      if (row.kind == Kind::tangent || !(row.mobility > 0)) continue;  // a contact's tangents go with its normal
      if (!with_friction || !with_tangents(s, r)) {
        const double wanted = std::max(row.impulse + (row.target - row_rate(row, x)) / row.mobility, 0.0);
        add_response(state, s, row, wanted - row.impulse, x);
        row.impulse = wanted;
        continue;
      }
      Row* rows = &s.rows[r];
      const Eigen::Vector3d rate(row_rate(rows[0], x), row_rate(rows[1], x), row_rate(rows[2], x));
      const Eigen::Vector3d impulse(rows[0].impulse, rows[1].impulse, rows[2].impulse);
      const Eigen::Vector3d wanted = project_contact_impulse(row.contact_block, rate, impulse, row.target, state.contacts[row.contact].friction);
      for (Eigen::Index i = 0; i < 3; ++i) {
        if (wanted[i] == impulse[i]) continue;
        add_response(state, s, rows[i], wanted[i] - impulse[i], x);
        rows[i].impulse = wanted[i];
      }
    }
  }
}

// Each contact's rows start from the impulse its place had last step (ContactMemory: the
// normal's, and the tangents' when it has friction); limit rows from none.
void warm_start(JointContactScratch& s, const std::vector<RigidContact>& contacts, double dt) {
  s.memory.begin_matching();
  for (std::size_t r = 0; r < s.rows.size(); ++r) {
    Row& row = s.rows[r];
    row.impulse = 0;
    if (row.kind != Kind::normal) continue;
    const Eigen::Vector3d impulse = s.memory.take(contacts[row.contact], dt);
    row.impulse = impulse[0];
    if (with_tangents(s, r)) s.rows[r + 1].impulse = impulse[1], s.rows[r + 2].impulse = impulse[2], r += 2;
  }
}

// The contacts' impulses as the next step's warm start.
void remember_impulses(JointContactScratch& s, const std::vector<RigidContact>& contacts, double dt) {
  s.memory.begin_recording();
  for (std::size_t r = 0; r < s.rows.size(); ++r) {
    const Row& row = s.rows[r];
    if (row.kind != Kind::normal) continue;
    const bool friction = with_tangents(s, r);
    s.memory.record(contacts[row.contact], Eigen::Vector3d(row.impulse, friction ? s.rows[r + 1].impulse : 0.0, friction ? s.rows[r + 2].impulse : 0.0));
  }
  s.memory.finish_recording(dt);
}

}  // namespace

void prepare_contacts_with_joints(LagrangeState& state) {
  JointContactScratch& s = state.contact_scratch;
  s.next_batch.assign(state.islands.size(), 0);
  std::vector<std::uint32_t> control_rows(state.islands.size(), 0);
  for (const ControlledJoint& joint : state.controls.joints) control_rows[state.island_of_body[state.constraints.outboard[joint.joint]]] += joint.count;
  // Room for every contact the scene reserved (RigidScene::contacts) and every limit, and for
  // the batches of the largest island with each limb end on each plane: a step that stays
  // within them allocates nothing.
  std::size_t batches = 0;
  for (std::size_t c = 0; c < state.islands.size(); ++c) {
    batches = std::max<std::size_t>(batches, 3 * 2 * state.islands[c].bodies.size() * std::max<std::size_t>(state.planes.size(), 1) + control_rows[c]);
  }
  s.rows.reserve(3 * state.contacts.capacity() + state.controls.rows.size());
  s.responses.reserve(batches * state.bodies.size());
  s.velocity.reserve(state.bodies.size()), s.displacement.reserve(state.bodies.size());
  s.memory.reserve(state.contacts.capacity());
}

void resolve_contacts_with_joints(LagrangeState& state, double dt, bool before_move) {
  JointContactScratch& s = state.contact_scratch;
  if (state.contacts.empty()) {
    s.memory.clear();  // a contact that comes back later starts cold
    return;
  }
  RigidBodyState& y = state.bodies.state;
  const std::size_t n = state.bodies.size();
  body_velocities(state, y);
  update_geometry(state, y);
  s.velocity.resize(n);
  for (std::size_t b = 0; b < n; ++b) s.velocity[b] << state.velocity[b], state.angular_velocity[b];
  build_rows(state, s, dt);
  measure_responses(state, s);

  // Velocities: each normal reaches its contact's target speed (its bounce, or before the move a
  // gap closed within the step); a limit comes at most to its bound within the step, and one
  // already past stops.
  for (Row& row : s.rows) {
    const RigidContact& contact = state.contacts[row.contact];  // a limit's is unused
    row.target = row.kind == Kind::limit ? -std::max(row.gap, 0.0) / dt : row.kind == Kind::normal ? contact_target_speed(contact, before_move, dt) : 0;
  }
  warm_start(s, state.contacts, dt);
  project_rows(state, s, s.velocity, /*with_friction=*/true, /*warm=*/true);
  remember_impulses(s, state.contacts, dt);
  for (std::size_t b = 0; b < n; ++b) {
    y.linear_momentum[b] = state.bodies.mass[b] * s.velocity[b].head<3>();
    y.angular_momentum[b] = state.world_inertia[b] * s.velocity[b].tail<3>();
  }

  // Positions: each normal moves out by its depth, less the separation it may keep (before the
  // move: the depth at the step's start, beyond the resting slop); a limit is not pushed past its
  // bound, and one past it is moved back onto it.
  for (Row& row : s.rows) {
    const RigidContact& contact = state.contacts[row.contact];
    const double push = before_move ? push_out_before_move(contact, state.settings, dt) : push_out_distance(contact, state.settings, dt);
    row.target = row.kind == Kind::limit ? -row.gap : row.kind == Kind::normal ? push : 0;
  }
  s.displacement.assign(n, Vector6::Zero());
  project_rows(state, s, s.displacement, /*with_friction=*/false, /*warm=*/false);
  for (std::size_t b = 0; b < n; ++b) {
    if (s.displacement[b].isZero()) continue;
    y.position[b] += s.displacement[b].head<3>();
    y.orientation[b] = (rotation_quaternion(s.displacement[b].tail<3>()) * y.orientation[b]).normalized();
  }
}

}  // namespace limber
