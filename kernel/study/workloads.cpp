#include "limber/kernel/study/workloads.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "limber/kernel/scene/generators.hpp"

namespace limber::study {

Scene heavy_end_chain(ChainRelease release) {
  constexpr int kLinks = 5;
  constexpr double kLength = 0.1;
  const double joint_mass[kLinks + 1] = {1.0, 1, 1, 1, 1, 2};  // at the pin (no effect), then the outer ends
  Model model;
  model.name = release == ChainRelease::arc ? "heavy-end chain, arc release" : "heavy-end chain, small 3-D release";
  model.settings.sleep.enabled = false;
  Vector3 head = Vector3::Zero();
  for (int k = 0; k < kLinks; ++k) {
    Vector3 direction;  // head → tail
    if (release == ChainRelease::arc) {
      const double angle = k * 5.0 * std::numbers::pi / 180;
      direction = Vector3(std::cos(angle), 0, -std::sin(angle));
    } else {
      direction = Vector3(0.15 * std::cos(1.3 * k), 0.15 * std::sin(1.3 * k), -1).normalized();
    }
    Body body;
    body.name = "link_" + std::to_string(k);
    body.shape = {ShapeType::capsule, kLength, 0.001};
    body.position = head + 0.5 * kLength * direction;
    body.axis = -direction;
    body.collision = {kLinkCollisionGroup, ~kLinkCollisionGroup};  // links do not meet links (generators.hpp)
    const double head_mass = k == 0 ? 0.5 : 0.5 * joint_mass[k];
    const double tail_mass = k == kLinks - 1 ? joint_mass[k + 1] : 0.5 * joint_mass[k + 1];
    body.point_masses = {PointMass{Vector3(0, 0, 0.5 * kLength), head_mass, 0}, PointMass{Vector3(0, 0, -0.5 * kLength), tail_mass, 0}};
    body.mass = head_mass + tail_mass;
    model.bodies.push_back(body);
    const Vector3 head_anchor(0, 0, 0.5 * kLength), tail_anchor(0, 0, -0.5 * kLength);
    model.joints.push_back(k == 0 ? spherical_joint("pin", kWorld, 0, Vector3::Zero(), head_anchor)
                                  : spherical_joint("joint_" + std::to_string(k), k - 1, k, tail_anchor, head_anchor));
    head += kLength * direction;
  }
  validate(model);
  MethodSettings methods;
  methods.verlet.joints = ParticleJoints::shared_particle;
  methods.verlet.limb_masses = LimbMasses::lumps;
  return {std::move(model), methods, {}};
}

Scene double_pendulum(double release_angle) {
  const Vector3 direction(std::sin(release_angle), 0, -std::cos(release_angle));
  Model model = make_chain_model({.links = 2, .link_length = 0.5, .link_mass = 1, .anchor = {0, 0, 1}, .direction = direction});
  model.name = "double pendulum";
  MethodSettings methods;
  methods.verlet.joints = ParticleJoints::shared_particle;
  return {std::move(model), methods, {}};
}

}  // namespace limber::study
