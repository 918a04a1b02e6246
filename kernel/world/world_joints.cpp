// The World's calls on joints (world.hpp): the motors' controls, the drives, held points.
#include <algorithm>
#include <cmath>
#include <string>

#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/methods/method_contract.hpp"
#include "limber/kernel/world/world.hpp"
#include "limber/kernel/world/world_internals.hpp"

namespace limber {

// --- Actuators

void World::set_controls(std::span<const double> controls) {
  std::vector<double>& kept = internals_->controls;
  if (controls.size() != kept.size()) {
    throw WorldError("set_controls: the model has " + std::to_string(kept.size()) + " actuators, got " + std::to_string(controls.size()) +
                     " controls");
  }
  for (std::size_t a = 0; a < controls.size(); ++a) {
    if (!std::isfinite(controls[a])) throw WorldError("set_controls: control " + std::to_string(a) + " ('" + model_.actuators[a].name + "') must be finite");
    try {
      require_actuator_supported(model_, method(), a, controls[a]);
    } catch (const ModelError& error) {
      throw WorldError(std::string("set_controls: ") + error.what());
    }
  }
  std::copy(controls.begin(), controls.end(), kept.begin());
  for (std::size_t a = 0; a < controls.size(); ++a) {
    if (controls[a] != 0) wake(body_id(static_cast<std::size_t>(model_.joints[static_cast<std::size_t>(model_.actuators[a].joint)].outboard)));
  }
}

std::span<const double> World::controls() const { return internals_->controls; }


// --- Drives

void World::set_joint_drive(JointId joint, const std::optional<JointDrive>& drive) {
  const std::size_t k = index(joint);
  Joint changed = model_.joints[k];
  changed.drive = drive;
  try {
    validate_joint(changed, model_, k);  // this joint alone: a retarget per frame costs O(1)
  } catch (const ModelError& error) {
    throw WorldError(std::string("set_joint_drive: ") + error.what());
  }
  if (current_drive(k).has_value() != drive.has_value()) {  // a drive row appears or goes: recompile
    auto& drives = internals_->drives;
    const auto before = drives.find(joint.slot);
    const std::optional<std::optional<JointDrive>> kept = before == drives.end() ? std::nullopt : std::optional(before->second);
    drives[joint.slot] = drive;
    try {
      recompile(model_, first_bodies_kept(model_.bodies.size(), model_.bodies.size()), internals_->joints.slots());
    } catch (...) {  // nothing changes
      if (kept) drives[joint.slot] = *kept;
      else drives.erase(joint.slot);
      throw;
    }
    return;
  }
  internals_->drives[joint.slot] = drive;
  if (!drive) return;
  std::visit([&](auto& state) { limber::set_joint_drive(state, k, *drive); }, internals_->state);
  wake(body_id(static_cast<std::size_t>(model_.joints[k].outboard)));
}

std::optional<JointDrive> World::joint_drive(JointId joint) const { return current_drive(index(joint)); }

// --- Held points

PinId World::pin(BodyId body, const Eigen::Vector3d& local_point) {
  check_vector(local_point, "pin");
  if (!capabilities(options_.method).holds) {
    refuse("pin", "holds points only through joints of its tree: a joint to the world added while the tree moves would re-root it; put the joint in the Model");
  }
  const std::size_t b = index(body);
  const Eigen::Vector3d world_point = std::visit([&](const auto& state) { return body_point(state, b, local_point); }, internals_->state);
  Joint joint = spherical_joint("pin " + std::to_string(internals_->pins_made), kWorld, static_cast<int>(b), world_point, local_point);
  const JointId id = add_joint(joint);
  ++internals_->pins_made;
  internals_->pins.push_back({id, std::nullopt, std::nullopt});
  return internals_->pin_handles.add(serial_);
}

void World::unpin(PinId pin) {
  const JointId joint = internals_->pins[index(pin, "unpin")].joint;
  remove_joint(joint);  // and the pin with it
}

void World::move_pin(PinId pin, const Eigen::Vector3d& world_target) {
  check_vector(world_target, "move_pin");
  WorldInternals::Pin& entry = internals_->pins[index(pin, "move_pin")];
  entry.target = world_target;
  wake(body_id(static_cast<std::size_t>(model_.joints[index(entry.joint)].outboard)));
}

Eigen::Vector3d World::pin_position(PinId pin) const {
  const JointId joint = internals_->pins[index(pin, "pin_position")].joint;
  return std::visit([&](const auto& state) { return world_anchor(state, model_, index(joint)); }, internals_->state);
}

}  // namespace limber
