#include "limber/kernel/world/world.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>
#include <type_traits>

#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/methods/method_contract.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/world/world_internals.hpp"

namespace limber {

namespace {

// Every method's state answers every call the World makes (methods/method_contract.hpp).
template <typename Variant>
struct EveryMethodKeepsTheContract;
template <typename... States>
struct EveryMethodKeepsTheContract<std::variant<States...>> {
  static constexpr bool value = (MethodContract<States> && ...);
};
static_assert(EveryMethodKeepsTheContract<MethodState>::value, "a method's state misses a call of method_contract.hpp");

std::string vector_text(const Eigen::Vector3d& v) {
  std::ostringstream text;
  text << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return text.str();
}

// An actuator's joint force for this step, explicit: taken at the state the step starts from (as
// MuJoCo's are), each method's way (apply_joint_force: the pair of loads ±force·a on the joint's
// bodies). A method that takes a servo implicitly answers apply_actuator itself (Featherstone,
// Lagrange: their bodies.hpp), and overload resolution prefers its non-template.
template <typename State>
void apply_actuator(State& state, const Actuator& actuator, double control) {
  const auto joint = static_cast<std::size_t>(actuator.joint);
  const CoordinateMotion now = actuator.kind == ActuatorKind::motor ? CoordinateMotion{} : coordinate_motion(state, joint, actuator.axis);
  const double amount = actuator_force(actuator, control, now.position, now.velocity);
  if (amount != 0) apply_joint_force(state, joint, actuator.axis, amount);
}

template <typename State>
void apply_actuators(State& state, const Model& model, const std::vector<double>& controls) {
  for (std::size_t a = 0; a < controls.size(); ++a) apply_actuator(state, model.actuators[a], controls[a]);
}

// Serials for the handles of each World made (0 is no World's).
std::atomic<std::uint32_t> next_world_serial{1};

}  // namespace

World::World(Model model, WorldOptions options)
    : model_(std::move(model)), options_(std::move(options)), serial_(next_world_serial.fetch_add(1)),
      internals_(std::make_unique<WorldInternals>()) {
  internals_->state = compile_method(model_, options_);
  for (std::size_t b = 0; b < model_.bodies.size(); ++b) internals_->bodies.add(serial_);
  for (std::size_t j = 0; j < model_.joints.size(); ++j) internals_->joints.add(serial_);
  for (std::size_t c = 0; c < model_.colliders.size(); ++c) internals_->colliders.add(serial_);
  for (std::size_t k = 0; k < model_.balls.size(); ++k) internals_->balls.add(serial_);
  internals_->controls.assign(model_.actuators.size(), 0.0);
  reset_loads();
  internals_->divergence = divergence_bounds(model_, observe_state(ObservationScope::divergence));
}

World::World(const Scene& scene, Method method) : World(scene.model, world_options(method, scene.methods)) {}
World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

// Sizes the per-body loads after a (re)compile, all zero.
void World::reset_loads() {
  const std::size_t bodies = model_.bodies.size();
  for (auto* loads : {&load_force_, &load_torque_, &impulse_force_, &impulse_torque_}) loads->assign(bodies, Eigen::Vector3d::Zero());
}

double World::time() const {
  return std::visit([](const auto& state) { return state.time; }, internals_->state);
}

Observation World::observe_state(ObservationScope scope) const {
  return std::visit([&](const auto& state) { return limber::observe(state, scope); }, internals_->state);
}

Observation World::observe() const {
  Observation out = observe_state(ObservationScope::full);
  if (out.widest_joint >= 0) out.widest_joint = static_cast<int>(model_joint_of(model_, static_cast<std::size_t>(out.widest_joint)));
  std::optional<WorldInternals::PenetrationGauge>& gauge = internals_->penetration_gauge;
  if (!gauge) gauge.emplace(WorldInternals::PenetrationGauge{LimbCollisions(model_), {}});
  segments(gauge->segments);
  out.penetration = deepest_penetration(model_, gauge->collisions, gauge->segments);
  return out;
}

void World::segments(std::vector<LimbSegment>& out) const {
  std::visit([&](const auto& state) { limb_segments(state, model_, out); }, internals_->state);
}

// --- Handles

BodyId World::body(std::string_view name) const {
  const int b = model_.find_body(name);
  if (b < 0) throw WorldError("body: no body called '" + std::string(name) + "'");
  return body_id(static_cast<std::size_t>(b));
}

JointId World::joint(std::string_view name) const {
  for (std::size_t j = 0; j < model_.joints.size(); ++j) {
    if (model_.joints[j].name == name) return internals_->joints.at(j, serial_);
  }
  throw WorldError("joint: no joint called '" + std::string(name) + "'");
}

std::vector<BodyId> World::bodies() const {
  std::vector<BodyId> out;
  for (std::size_t b = 0; b < model_.bodies.size(); ++b) out.push_back(body_id(b));
  return out;
}

BodyId World::body_id(std::size_t b) const { return internals_->bodies.at(b, serial_); }

const Body& World::body_description(BodyId body) const { return model_.bodies[index(body)]; }

template <typename Id>
void World::check_world(Id id, std::string_view kind, std::string_view call) const {
  if (id.world != serial_) {
    throw WorldError((call.empty() ? std::string() : std::string(call) + ": ") + std::string(kind) + " handle " + std::to_string(id.slot) +
                     (id.world == 0 ? ": not a handle a World gave" : ": from another World (each World's handles are its own)"));
  }
}

namespace {

}  // namespace

std::size_t World::index(BodyId body) const {
  check_world(body, "body");
  return position_of(internals_->bodies, body, "body");
}

std::size_t World::index(JointId joint) const {
  check_world(joint, "joint");
  return position_of(internals_->joints, joint, "joint");
}

ColliderId World::collider(std::string_view name) const {
  for (std::size_t c = 0; c < model_.colliders.size(); ++c) {
    if (model_.colliders[c].name == name) return internals_->colliders.at(c, serial_);
  }
  throw WorldError("collider: no collider called '" + std::string(name) + "'");
}

std::size_t World::index(ColliderId collider) const {
  check_world(collider, "collider");
  return position_of(internals_->colliders, collider, "collider");
}

[[noreturn]] void World::refuse(std::string_view call, std::string_view why) const {
  throw WorldError(std::string(call) + ": the " + std::string(method_name(options_.method)) + " method " + std::string(why));
}

void World::check_vector(const Eigen::Vector3d& v, std::string_view call) const {
  if (!v.allFinite()) throw WorldError(std::string(call) + ": must be finite, got " + vector_text(v));
}

// --- Stepping

StepStatus World::step(double dt) {
  MethodState& state = internals_->state;
  const double minimum = std::visit([](const auto& s) { return minimum_time_step(s); }, state);
  if (!valid_time_step(dt, minimum)) {  // the method's guard refuses it and records the refusal
    internals_->report = std::visit([&](auto& s) { return limber::step(s, dt); }, state);
    return internals_->report.status;
  }
  // This step's loads: forces and torques, and impulses as their force over the step.
  for (std::size_t b = 0; b < load_force_.size(); ++b) {
    load_force_[b] += impulse_force_[b] / dt, load_torque_[b] += impulse_torque_[b] / dt;
    impulse_force_[b].setZero(), impulse_torque_[b].setZero();
  }
  StepReport report = std::visit(
      [&](auto& s) {
        apply_actuators(s, model_, internals_->controls);
        for (std::size_t b = 0; b < load_force_.size(); ++b) {
          if (load_force_[b].isZero(0) && load_torque_[b].isZero(0)) continue;
          apply_body_load(s, b, load_force_[b], load_torque_[b]);
        }
        for (const WorldInternals::Pin& pin : internals_->pins) {
          if (pin.target) move_world_anchor(s, model_, index(pin.joint), *pin.target);
        }
        return limber::step(s, dt);
      },
      state);
  // After the step, in this order: the shared divergence check, the drives' release.
  if (report.status == StepStatus::ok && options_.divergence_check) report.status = check_divergence(observe_state(ObservationScope::divergence), internals_->divergence);
  internals_->report = report;
  if (release_drives_after_impact(state)) release_drives();
  for (std::size_t b = 0; b < load_force_.size(); ++b) load_force_[b].setZero(), load_torque_[b].setZero();
  for (WorldInternals::Pin& pin : internals_->pins) {
    if (pin.target) pin.anchor = pin.target;  // where a recompile holds the point
    pin.target.reset();
  }
  return report.status;
}

// The state has made every drive limp (release_drives_after_impact): so are the World's, which
// a recompile reads. Allocates nothing: the drives set before are made limp where they are.
void World::release_drives() {
  drives_released_ = true;
  for (auto& [slot, drive] : internals_->drives) {
    if (drive) drive->stiffness = drive->damping = 0;
  }
}

std::optional<JointDrive> World::current_drive(std::size_t joint) const {
  const auto& drives = internals_->drives;
  if (const auto set = drives.find(internals_->joints.slot(joint)); set != drives.end()) return set->second;
  std::optional<JointDrive> drive = model_.joints[joint].drive;
  if (drive && drives_released_) drive->stiffness = drive->damping = 0;
  return drive;
}

Model World::as_compiled(Model edited, const std::vector<std::uint32_t>& joint_slots) const {
  if (internals_->drives.empty() && internals_->pins.empty() && !drives_released_) return edited;
  std::unordered_map<std::uint32_t, std::size_t> joint_of_slot;
  for (std::size_t j = 0; j < joint_slots.size(); ++j) {
    if (joint_slots[j] == kNewJoint) continue;  // an added joint keeps its own drive
    joint_of_slot[joint_slots[j]] = j;
    std::optional<JointDrive>& drive = edited.joints[j].drive;
    if (drive && drives_released_) drive->stiffness = drive->damping = 0;
  }
  for (const auto& [slot, drive] : internals_->drives) {
    if (const auto j = joint_of_slot.find(slot); j != joint_of_slot.end()) edited.joints[j->second].drive = drive;
  }
  for (const WorldInternals::Pin& pin : internals_->pins) {
    const auto j = joint_of_slot.find(pin.joint.slot);
    if (pin.anchor && j != joint_of_slot.end()) edited.joints[j->second].inboard_anchor = *pin.anchor;
  }
  return edited;
}

// --- Reading

namespace {

// A bulk read-out's span has one entry a body, or the call is refused.
void check_bulk_size(std::string_view call, std::string_view entry, std::size_t bodies, std::size_t size) {
  if (size != bodies) {
    throw WorldError(std::string(call) + ": takes one " + std::string(entry) + " a body, " + std::to_string(bodies) + "; got " + std::to_string(size));
  }
}

}  // namespace

Pose World::pose(BodyId body) const {
  const std::size_t b = index(body);
  return std::visit([&](const auto& state) { return body_pose(state, b); }, internals_->state);
}

Motion World::motion(BodyId body) const {
  const std::size_t b = index(body);
  return std::visit([&](const auto& state) { return body_motion(state, b); }, internals_->state);
}

void World::poses(std::span<Pose> out) const {
  check_bulk_size("poses", "Pose", model_.bodies.size(), out.size());
  std::visit(
      [&](const auto& state) {
        for (std::size_t b = 0; b < out.size(); ++b) out[b] = body_pose(state, b);
      },
      internals_->state);
}

void World::motions(std::span<Motion> out) const {
  check_bulk_size("motions", "Motion", model_.bodies.size(), out.size());
  std::visit(
      [&](const auto& state) {
        for (std::size_t b = 0; b < out.size(); ++b) out[b] = body_motion(state, b);
      },
      internals_->state);
}

// --- Loads

// Adds `amount` at `world_point` to the body's `linear` entry, and its moment about the body's
// centre of mass to its `angular` entry; wakes the body.
void World::add_at_point(BodyId body, const Eigen::Vector3d& amount, const Eigen::Vector3d& world_point,
                         std::vector<Eigen::Vector3d>& linear, std::vector<Eigen::Vector3d>& angular) {
  const std::size_t b = index(body);
  const Eigen::Vector3d centre = std::visit([&](const auto& state) { return body_centre_of_mass(state, b); }, internals_->state);
  linear[b] += amount;
  angular[b] += (world_point - centre).cross(amount);
  wake(body);
}

void World::apply_force(BodyId body, const Eigen::Vector3d& force, const Eigen::Vector3d& world_point) {
  check_vector(force, "apply_force"), check_vector(world_point, "apply_force");
  add_at_point(body, force, world_point, load_force_, load_torque_);
}

void World::apply_impulse(BodyId body, const Eigen::Vector3d& impulse, const Eigen::Vector3d& world_point) {
  check_vector(impulse, "apply_impulse"), check_vector(world_point, "apply_impulse");
  add_at_point(body, impulse, world_point, impulse_force_, impulse_torque_);
}

void World::apply_torque(BodyId body, const Eigen::Vector3d& torque) {
  check_vector(torque, "apply_torque");
  load_torque_[index(body)] += torque;
  wake(body);
}

void World::apply_joint_torque(JointId joint, const Eigen::Vector3d& torque) {
  check_vector(torque, "apply_joint_torque");
  const Joint& j = model_.joints[index(joint)];
  load_torque_[static_cast<std::size_t>(j.outboard)] += torque;
  wake(body_id(static_cast<std::size_t>(j.outboard)));
  if (j.inboard != kWorld) load_torque_[static_cast<std::size_t>(j.inboard)] -= torque;
}

// The position of `pin` in internals_->pins, or a WorldError naming `call`.
std::size_t World::index(PinId pin, std::string_view call) const {
  check_world(pin, "pin", call);
  return position_of(internals_->pin_handles, pin, "pin", call);
}

// --- Sleeping

void World::wake(BodyId body) {
  const std::size_t b = index(body);
  std::visit([&](auto& state) { wake_body(state, b); }, internals_->state);
}

void World::wake_all() {
  for (std::size_t b = 0; b < model_.bodies.size(); ++b) wake(body_id(b));
}

const StepReport& World::last_report() const { return internals_->report; }

void World::sleep(BodyId body) {
  const std::size_t b = index(body);
  std::visit([&](auto& state) { sleep_body(state, b); }, internals_->state);
}

bool World::sleeping(BodyId body) const {
  const std::size_t b = index(body);
  return std::visit([&](const auto& state) { return body_sleeping(state, b); }, internals_->state);
}

// --- Teleport

void World::teleport(BodyId body, const Pose& pose, const Motion& motion) {
  check_vector(pose.position, "teleport"), check_vector(motion.linear, "teleport"), check_vector(motion.angular, "teleport");
  const double norm = pose.orientation.norm();
  if (!pose.orientation.coeffs().allFinite() || !(std::abs(norm - 1) <= 1e-3)) {
    const Eigen::Quaterniond& q = pose.orientation;
    std::ostringstream got;
    got << "(" << q.w() << ", " << q.x() << ", " << q.y() << ", " << q.z() << ")";
    throw WorldError("teleport: orientation must be a finite unit quaternion (w, x, y, z), got " + got.str());
  }
  const std::size_t b = index(body);
  const Pose normalized{pose.position, pose.orientation.normalized()};
  const bool moved = std::visit(
      [&](auto& state) {
        if (!teleport_body(state, b, normalized, motion)) return false;
        wake_body(state, b);
        return true;
      },
      internals_->state);
  if (!moved) {
    refuse("teleport", "moves only a body whose coordinates are its own (a floating root); '" + model_.bodies[b].name + "' hangs from a joint");
  }
  internals_->divergence.start_energy = observe_state(ObservationScope::divergence).energy();  // a teleport may put energy in: measure from here
}

// --- Structure

BodyId World::add_body(const Body& body) {
  Model edited = model_;
  edited.bodies.push_back(body);
  recompile(edited, first_bodies_kept(edited.bodies.size(), model_.bodies.size()), internals_->joints.slots());
  return internals_->bodies.add(serial_);
}

JointId World::add_joint(const Joint& joint) {
  Model edited = model_;
  edited.joints.push_back(joint);
  std::vector<std::uint32_t> slots = internals_->joints.slots();
  slots.push_back(kNewJoint);
  recompile(edited, first_bodies_kept(edited.bodies.size(), edited.bodies.size()), slots);
  const JointId id = internals_->joints.add(serial_);
  if (drives_released_ && joint.drive) internals_->drives[id.slot] = joint.drive;  // released before it came
  return id;
}

void World::remove_joint(JointId joint) {
  const std::size_t j = index(joint);
  Model edited = model_;
  edited.joints.erase(edited.joints.begin() + static_cast<std::ptrdiff_t>(j));
  std::vector<char> kept(model_.joints.size(), 1);
  kept[j] = 0;
  keep_joints(kept, edited, first_bodies_kept(edited.bodies.size(), edited.bodies.size()));
}

// Recompiles `edited`, whose joints are the old ones kept[j] marks, in order; then forgets the
// others' handles, drives and pins.
void World::keep_joints(const std::vector<char>& kept, Model edited, const std::vector<std::int64_t>& old_body_of_new) {
  std::vector<std::uint32_t> slots;
  std::vector<int> new_joint(kept.size(), -1);
  for (std::size_t j = 0; j < kept.size(); ++j) {
    if (kept[j]) new_joint[j] = static_cast<int>(slots.size()), slots.push_back(internals_->joints.slot(j));
  }
  // The kept joints' actuators, renumbered, and their controls.
  std::vector<double> controls;
  edited.actuators.clear();
  for (std::size_t a = 0; a < model_.actuators.size(); ++a) {
    Actuator actuator = model_.actuators[a];
    actuator.joint = new_joint[static_cast<std::size_t>(actuator.joint)];
    if (actuator.joint < 0) continue;
    edited.actuators.push_back(actuator), controls.push_back(internals_->controls[a]);
  }
  recompile(edited, old_body_of_new, slots);
  internals_->controls = std::move(controls);
  std::vector<char> pin_kept(internals_->pins.size(), 1);
  for (std::size_t j = 0; j < kept.size(); ++j) {
    if (kept[j]) continue;
    const std::uint32_t slot = internals_->joints.slot(j);
    internals_->drives.erase(slot);
    for (std::size_t k = 0; k < internals_->pins.size(); ++k) pin_kept[k] &= internals_->pins[k].joint.slot != slot ? 1 : 0;
  }
  internals_->joints.keep(kept);
  internals_->pin_handles.keep(pin_kept);
  std::size_t next = 0;
  for (std::size_t k = 0; k < internals_->pins.size(); ++k) {
    if (pin_kept[k]) internals_->pins[next++] = internals_->pins[k];
  }
  internals_->pins.resize(next);
}

void World::remove_body(BodyId body) {
  const std::size_t removed = index(body);
  Model edited = model_;
  edited.bodies.erase(edited.bodies.begin() + static_cast<std::ptrdiff_t>(removed));
  std::vector<char> kept(model_.joints.size(), 1);
  edited.joints.clear();
  for (std::size_t j = 0; j < model_.joints.size(); ++j) {
    Joint joint = model_.joints[j];
    if (joint.inboard == static_cast<int>(removed) || joint.outboard == static_cast<int>(removed)) {
      kept[j] = 0;
      continue;
    }
    if (joint.inboard > static_cast<int>(removed)) --joint.inboard;
    if (joint.outboard > static_cast<int>(removed)) --joint.outboard;
    edited.joints.push_back(joint);
  }
  std::vector<std::int64_t> old_body_of_new;
  for (std::size_t b = 0; b < model_.bodies.size(); ++b) {
    if (b != removed) old_body_of_new.push_back(static_cast<std::int64_t>(b));
  }
  keep_joints(kept, edited, old_body_of_new);
  internals_->bodies.erase(removed);
}

std::vector<BodyId> World::add_model(const Model& other, std::string_view prefix, const Eigen::Vector3d& offset) {
  check_vector(offset, "add_model");
  Model edited = model_;
  const std::size_t base = model_.bodies.size(), joint_base = model_.joints.size();
  append_model(edited, other, prefix, offset);
  std::vector<std::uint32_t> slots = internals_->joints.slots();
  slots.resize(edited.joints.size(), kNewJoint);
  recompile(edited, first_bodies_kept(edited.bodies.size(), base), slots);
  std::vector<BodyId> added;
  for (std::size_t b = base; b < model_.bodies.size(); ++b) added.push_back(internals_->bodies.add(serial_));
  for (std::size_t j = joint_base; j < model_.joints.size(); ++j) {
    const JointId id = internals_->joints.add(serial_);
    if (drives_released_ && model_.joints[j].drive) internals_->drives[id.slot] = model_.joints[j].drive;  // released before it came
  }
  return added;
}

// Colliders change no body: every body keeps its index and its state.
ColliderId World::add_collider(const StaticCollider& collider) {
  Model edited = model_;
  edited.colliders.push_back(collider);
  recompile(edited, first_bodies_kept(edited.bodies.size(), edited.bodies.size()), internals_->joints.slots());
  return internals_->colliders.add(serial_);
}

void World::remove_collider(ColliderId collider) {
  const std::size_t c = index(collider);
  Model edited = model_;
  edited.colliders.erase(edited.colliders.begin() + static_cast<std::ptrdiff_t>(c));
  recompile(edited, first_bodies_kept(edited.bodies.size(), edited.bodies.size()), internals_->joints.slots());
  internals_->colliders.erase(c);
}

// --- Balls

BallId World::add_ball(const Ball& ball) {
  Model edited = model_;
  edited.balls.push_back(ball);
  recompile(edited, first_bodies_kept(edited.bodies.size(), edited.bodies.size()), internals_->joints.slots());
  return internals_->balls.add(serial_);
}

void World::remove_ball(BallId ball) {
  const std::size_t k = index(ball);
  Model edited = model_;
  edited.balls.erase(edited.balls.begin() + static_cast<std::ptrdiff_t>(k));
  std::vector<std::int64_t> old_ball_of_new;
  for (std::size_t old = 0; old < model_.balls.size(); ++old) {
    if (old != k) old_ball_of_new.push_back(static_cast<std::int64_t>(old));
  }
  recompile(edited, first_bodies_kept(edited.bodies.size(), edited.bodies.size()), internals_->joints.slots(), std::move(old_ball_of_new));
  internals_->balls.erase(k);
}

std::vector<BallId> World::balls() const {
  std::vector<BallId> out;
  for (std::size_t k = 0; k < model_.balls.size(); ++k) out.push_back(internals_->balls.at(k, serial_));
  return out;
}

std::size_t World::index(BallId ball) const {
  check_world(ball, "ball");
  return position_of(internals_->balls, ball, "ball");
}

BallMotion World::ball(BallId ball) const {
  const std::size_t k = index(ball);
  return std::visit([&](const auto& state) { return ball_motion(state, k); }, internals_->state);
}

// Compiles `edited` and carries across, for every body whose old index is old_body_of_new[b]
// (−1: new), the state the old one had; then makes `edited` the model. Nothing changes when the
// compile throws.
void World::recompile(const Model& edited, const std::vector<std::int64_t>& old_body_of_new,
                      const std::vector<std::uint32_t>& joint_handles, std::optional<std::vector<std::int64_t>> old_ball_of_new) {
  Survivors survivors{old_body_of_new, {}};
  // The maximal-coordinate methods run serial joints through virtual links: those carry too.
  if (options_.method != Method::featherstone) survivors.bodies = with_virtual_links(model_, edited, std::move(survivors.bodies));
  if (old_ball_of_new) {
    survivors.balls = std::move(*old_ball_of_new);
  } else {
    survivors.balls = first_bodies_kept(edited.balls.size(), std::min(edited.balls.size(), model_.balls.size()));
  }
  MethodState next = compile_method(as_compiled(edited, joint_handles), options_);
  std::string problem;
  const bool carried = std::visit(
      [&](auto& fresh) {
        using State = std::decay_t<decltype(fresh)>;
        return carry_state(std::get<State>(internals_->state), model_, fresh, edited, survivors, problem);
      },
      next);
  if (!carried) refuse("a structural edit", problem);
  internals_->state = std::move(next);
  internals_->penetration_gauge.reset();  // measured against the edited Model's pairs and colliders
  model_ = edited;
  reset_loads();
  internals_->divergence = divergence_bounds(model_, observe_state(ObservationScope::divergence));
}

}  // namespace limber
