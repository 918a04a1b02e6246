// How compile() gives particle limbs frames and turns joints beyond "two limb ends held
// together" into joint rows (kernel/particles/joint_rows.hpp). Internal to kernel/verlet.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/particles/joint_rows.hpp"

namespace limber::frames {

/// The length of a limb's particle axis, head to tail, m: its shape's, or for a sphere (a capsule
/// of length 0, which has no axis) √2 × its radius along its body z. Two end particles of m/2
/// there give a sphere's transverse inertia 5/4 of a solid sphere's (2/5 m r²); with a centre
/// particle (limb_masses "inertia"), exactly it.
double axis_length(const Body& body);

/// Which axis end point an anchor is (the particle method's head and tail particles), if any.
enum class End : std::uint8_t { head, tail };
std::optional<End> anchor_end(const Body& body, const Vector3& anchor);

/// Moves the joint anchors that the particle method may place elsewhere without changing the
/// joint, so that each limb's off-axis anchors lie in one plane through its axis (its frame's,
/// which plan() requires): a fixed joint's to its inboard limb's centre (any common point welds
/// the same two bodies), and a revolute joint's along its hinge axis into the plane its limb's
/// first off-axis anchor set. Returns whether it moved any; leaves for plan() to refuse what no
/// such move fits. Exact: every joint holds the same relative motion as before.
bool place_anchors(Model& model);
/// Whether place_anchors would move anything (some limb's off-axis anchors are not in one plane).
bool anchors_to_place(const Model& model);

/// What compile needs to know before it places particles.
struct Plan {
  std::vector<bool> framed;        ///< per body: carries frame particles F⁺, F⁻
  std::vector<Vector3> direction;  ///< per body: v̂, unit, body frame, ⟂ z (framed bodies)
  std::vector<double> spacing;     ///< per body: δ, m
  std::vector<double> frame_mass;  ///< per body: the mass of each frame particle, kg
  std::vector<bool> point_row;     ///< per joint: held by a point row (an anchor off the ends)
  bool any_rows = false;           ///< some joint needs rows, or some limb a frame
  bool any_frames = false;
};

/// Decides frames and rows for `model` under the particle method, and takes each frame's mass
/// from the limb's particles (`head`, `centre`, `tail`: kg, updated). Throws ModelError naming the
/// joint or body for what the particle method cannot represent.
Plan plan(const Model& model, bool shared_particles, std::vector<std::array<double, 3>>& limb_masses);

/// The particles of one limb as joint rows name them: head, tail, F⁺, F⁻, centre (the null
/// particle where absent).
using LimbParticles = std::array<std::uint32_t, kJointRowSideParticles>;

/// The rows of `model`'s frames and joints. `limb_particles(b)` gives body b's particles,
/// `pin_particle(k)` the world particle of joint k (to the world), `island_of_body(b)` its island.
JointRowSet build_rows(const Model& model, const Plan& plan, const std::function<LimbParticles(std::size_t)>& limb_particles,
                       const std::function<std::uint32_t(std::size_t)>& pin_particle,
                       const std::function<std::uint32_t(std::size_t)>& island_of_body, std::uint32_t null_particle);

}  // namespace limber::frames
