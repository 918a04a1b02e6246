// A rope held by a moving hand: a 30-link rope whose first link's head is held (World::pin)
// and carried around a circle (World::move_pin, a kinematic target), printing the hand and the
// rope's free end every half second.
//
//   build/tools/examples/rope_in_hand [particles|lagrange]    (default particles)
//
// (Featherstone refuses a held point that moves; the stiff springs would need far smaller steps
// for links of 10 g.)
#include <cmath>
#include <cstdio>
#include <string>

#include <limber/kernel/scene/generators.hpp>
#include <limber/kernel/world/world.hpp>

int main(int argc, char** argv) {
  const std::string method_name = argc > 1 ? argv[1] : "particles";
  limber::WorldOptions options;
  if (method_name == "lagrange") options.method = limber::Method::lagrange;
  else if (method_name != "particles") {
    std::fprintf(stderr, "rope_in_hand: unknown method '%s' (particles or lagrange)\n", method_name.c_str());
    return 2;
  }
  // 30 links of 2 cm and 10 g hanging from (0, 0, 1); the particle method makes each joint one
  // particle and projects by the rattle rule in 8 substeps of 2 sweeps a frame.
  limber::Model rope = limber::make_chain_model(
      {.links = 30, .link_length = 0.02, .link_mass = 0.01, .anchor = {0, 0, 1}, .direction = {0, 0, -1}, .pinned = false});
  rope.settings.damping = 0.2;
  options.particles.verlet.joints = limber::ParticleJoints::shared_particle;
  options.particles.relaxation.projection = limber::ProjectionRule::rattle;
  options.particles.relaxation.substeps = 8;
  options.particles.relaxation.iterations = 2;
  limber::World world(rope, options);

  const limber::BodyId first = world.body("link_0"), last = world.body("link_29");
  const limber::PinId hand = world.pin(first, {0, 0, 0.01});  // link_0's head
  const Eigen::Vector3d centre = world.pin_position(hand);
  // Frames of 1/60 s: the particle method takes one step a frame; Lagrange's constraint drift on
  // these light, thin links needs steps of 1/1200 s.
  const int steps_per_frame = options.method == limber::Method::particles ? 1 : 20;
  const double dt = 1.0 / 60, h = dt / steps_per_frame, radius = 0.15, turn = 2.0;  // s, s, m, rad/s
  for (int frame = 1; frame <= 240; ++frame) {
    for (int k = 1; k <= steps_per_frame; ++k) {
      const double angle = turn * ((frame - 1) * dt + k * h);
      world.move_pin(hand, centre + radius * Eigen::Vector3d(std::cos(angle) - 1, std::sin(angle), 0));
      if (world.step(h) != limber::StepStatus::ok) {
        std::fprintf(stderr, "rope_in_hand: diverged at frame %d\n", frame);
        return 1;
      }
    }
    if (frame % 30 == 0) {
      const Eigen::Vector3d held = world.pin_position(hand);
      const limber::Pose end = world.pose(last);
      std::printf("t %.2f s  hand (%.3f, %.3f, %.3f)  rope end (%.3f, %.3f, %.3f) q (%.3f, %.3f, %.3f, %.3f)\n", frame * dt,
                  held.x(), held.y(), held.z(), end.position.x(), end.position.y(), end.position.z(), end.orientation.w(),
                  end.orientation.x(), end.orientation.y(), end.orientation.z());
    }
  }
  return 0;
}
