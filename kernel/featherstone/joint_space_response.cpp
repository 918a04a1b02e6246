#include "limber/kernel/featherstone/joint_space_response.hpp"

#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/featherstone/step.hpp"

namespace limber {

using namespace joint_space;

void impulse_response(FeatherstoneState& state, std::size_t island) { impulse_response(state, island, state.contact.articulated); }

void impulse_response(FeatherstoneState& state, std::size_t island, const DynamicsWorkspace& w) {
  const ArticulatedTree& tree = state.tree;
  JointSpaceContactScratch& s = state.contact;
  const int begin = state.island_begin[island], end = state.island_begin[island + 1];
  // Inward: u_i = τ_i − S_iᵀ p_i (the generalized impulse), p_λ += λX_i*(p_i + U_i D_i⁻¹ u_i).
  for (int i = end - 1; i >= begin; --i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    SpatialVector through = s.spatial_impulse[index];
    s.spatial_impulse[index].setZero();
    bool untouched = through.isZero(0);  // no impulse on this body, its joint or below it: u_i = 0
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k > 0) {
        auto applied = s.joint_impulse.template segment<k>(offset);
        if (untouched && applied.isZero(0)) {
          s.joint_bias.template segment<k>(offset).setZero();
          return;
        }
        untouched = false;
        const Eigen::Matrix<double, k, 1> u = applied - project_on_joint<k>(body, through);
        applied.setZero();
        s.joint_bias.template segment<k>(offset) = u;
        through.noalias() += w.projected_inertia.template middleCols<k>(offset) * (w.joint_inertia_inverse.template block<k, k>(0, offset) * u);
      }
    });
    if (body.parent >= 0 && !untouched) {
      s.spatial_impulse[static_cast<std::size_t>(body.parent)] += w.parent_to_body[index].transpose_apply_force(through);
    }
  }
  // Outward: Δv_i = D_i⁻¹(u_i − U_iᵀ a'), Δa_i = a' + S_i Δv_i with a' = ⁱX_λ Δa_λ.
  for (int i = begin; i < end; ++i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    SpatialVector change = body.parent >= 0 ? w.parent_to_body[index].apply_motion(s.body_change[static_cast<std::size_t>(body.parent)])
                                            : SpatialVector::Zero();
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k > 0) {
        const Eigen::Matrix<double, k, 1> rates =
            w.joint_inertia_inverse.template block<k, k>(0, offset) *
            (s.joint_bias.template segment<k>(offset) - w.projected_inertia.template middleCols<k>(offset).transpose() * change);
        s.joint_change.template segment<k>(offset) = rates;
        change += joint_motion<k>(body, rates);
      }
    });
    s.body_change[index] = change;
  }
}

Eigen::Matrix3d joint_block_response(FeatherstoneState& state, std::size_t island, int offset, int dofs) {
  Eigen::Matrix3d k = Eigen::Matrix3d::Zero();
  for (int m = 0; m < dofs; ++m) {
    state.contact.joint_impulse[offset + m] = 1;
    impulse_response(state, island);
    for (int r = 0; r < dofs; ++r) k(r, m) = state.contact.joint_change[offset + r];
  }
  return 0.5 * (k + k.transpose());  // symmetric in exact arithmetic
}

}  // namespace limber
