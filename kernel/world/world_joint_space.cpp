// World's joint-space calls (world.hpp, "Joint space"): reduced coordinates answer them
// (kernel/featherstone/joint_space.hpp); the other methods refuse each by name.
#include <cmath>
#include <type_traits>

#include "limber/kernel/featherstone/joint_space.hpp"
#include "limber/kernel/metrics/divergence.hpp"
#include "limber/kernel/world/world.hpp"
#include "limber/kernel/world/world_internals.hpp"

namespace limber {
namespace {

template <typename State>
concept HasJointSpace = requires(const State& state, const Model& model) { joint_space_layout(state, model); };

// answer(state, layout) on a state with joint coordinates; refuse() (which throws) otherwise.
template <typename Result, typename Answer, typename Refuse>
Result with_joint_space(MethodState& state, const Model& model, Answer answer, Refuse refuse) {
  return std::visit(
      [&](auto& s) -> Result {
        if constexpr (HasJointSpace<std::remove_cvref_t<decltype(s)>>) {
          return answer(s, joint_space_layout(s, model));
        } else {
          refuse();
          return Result();
        }
      },
      state);
}

}  // namespace

void World::refuse_joint_space(std::string_view call) const {
  refuse(call, "has no joint coordinates (its bodies are maximal coordinates); featherstone has");
}

std::vector<std::string> World::joint_space_names() const {
  return with_joint_space<std::vector<std::string>>(
      internals_->state, model_, [](auto&, const JointSpaceLayout& layout) { return layout.names; }, [this] { refuse_joint_space("joint_space_names"); });
}

std::vector<std::string> World::joint_position_names() const {
  return with_joint_space<std::vector<std::string>>(
      internals_->state, model_, [](auto&, const JointSpaceLayout& layout) { return layout.position_names; },
      [this] { refuse_joint_space("joint_position_names"); });
}

Eigen::VectorXd World::joint_positions() const {
  return with_joint_space<Eigen::VectorXd>(
      internals_->state, model_, [](auto& s, const JointSpaceLayout& layout) { return limber::joint_positions(s, layout); },
      [this] { refuse_joint_space("joint_positions"); });
}

Eigen::VectorXd World::joint_velocities() const {
  return with_joint_space<Eigen::VectorXd>(
      internals_->state, model_, [](auto& s, const JointSpaceLayout& layout) { return limber::joint_velocities(s, layout); },
      [this] { refuse_joint_space("joint_velocities"); });
}

Eigen::MatrixXd World::joint_mass_matrix() const {
  return with_joint_space<Eigen::MatrixXd>(
      internals_->state, model_, [](auto& s, const JointSpaceLayout& layout) { return limber::joint_mass_matrix(s, layout); },
      [this] { refuse_joint_space("joint_mass_matrix"); });
}

Eigen::VectorXd World::joint_bias_forces() const {
  return with_joint_space<Eigen::VectorXd>(
      internals_->state, model_, [](auto& s, const JointSpaceLayout& layout) { return limber::joint_bias_forces(s, layout); },
      [this] { refuse_joint_space("joint_bias_forces"); });
}

Eigen::VectorXd World::joint_passive_forces() const {
  return with_joint_space<Eigen::VectorXd>(
      internals_->state, model_,
      [&](auto& s, const JointSpaceLayout& layout) { return limber::joint_passive_forces(s, model_, layout, internals_->controls); },
      [this] { refuse_joint_space("joint_passive_forces"); });
}

Eigen::VectorXd World::joint_accelerations(const Eigen::VectorXd& forces) const {
  if (!forces.allFinite()) throw WorldError("joint_accelerations: the forces must be finite");
  try {
    return with_joint_space<Eigen::VectorXd>(
        internals_->state, model_, [&](auto& s, const JointSpaceLayout& layout) { return forward_joint_dynamics(s, layout, forces); },
        [this] { refuse_joint_space("joint_accelerations"); });
  } catch (const std::invalid_argument& error) {
    throw WorldError(std::string("joint_accelerations: ") + error.what());
  }
}

Eigen::VectorXd World::inverse_dynamics(const Eigen::VectorXd& accelerations) const {
  if (!accelerations.allFinite()) throw WorldError("inverse_dynamics: the accelerations must be finite");
  try {
    return with_joint_space<Eigen::VectorXd>(
        internals_->state, model_, [&](auto& s, const JointSpaceLayout& layout) { return inverse_joint_dynamics(s, layout, accelerations); },
        [this] { refuse_joint_space("inverse_dynamics"); });
  } catch (const std::invalid_argument& error) {
    throw WorldError(std::string("inverse_dynamics: ") + error.what());
  }
}

std::vector<JointReaction> World::joint_reactions(const Eigen::VectorXd& accelerations) const {
  if (!accelerations.allFinite()) throw WorldError("joint_reactions: the accelerations must be finite");
  try {
    return with_joint_space<std::vector<JointReaction>>(
        internals_->state, model_, [&](auto& s, const JointSpaceLayout& layout) { return limber::joint_reactions(s, model_, layout, accelerations); },
        [this] { refuse_joint_space("joint_reactions"); });
  } catch (const std::invalid_argument& error) {
    throw WorldError(std::string("joint_reactions: ") + error.what());
  }
}

void World::set_joint_state(const Eigen::VectorXd& positions, const Eigen::VectorXd& velocities) {
  if (!positions.allFinite() || !velocities.allFinite()) throw WorldError("set_joint_state: the positions and velocities must be finite");
  try {
    with_joint_space<int>(
        internals_->state, model_,
        [&](auto& s, const JointSpaceLayout& layout) { return limber::set_joint_state(s, layout, positions, velocities), 0; },
        [this] { refuse_joint_space("set_joint_state"); });
  } catch (const std::invalid_argument& error) {
    throw WorldError(std::string("set_joint_state: ") + error.what());
  }
  wake_all();
  internals_->divergence = divergence_bounds(model_, observe_state(ObservationScope::divergence));  // a teleport: measure from here
}

}  // namespace limber
