// A ragdoll hit: the thesis's humanoid, knocked by the scene's elastic ball, then shoved twice
// more (an impulse at the head, a torque on the basin), printing every body's transform every
// half second — what an engine would copy into its renderer.
//
//   build/tools/examples/ragdoll [particles|springs|lagrange|featherstone]    (default particles)
#include <cmath>
#include <cstdio>
#include <string>

#include <limber/kernel/scene/scene_file.hpp>
#include <limber/kernel/world/world.hpp>

int main(int argc, char** argv) {
  const std::string method_name = argc > 1 ? argv[1] : "particles";
  limber::Method method = limber::Method::particles;
  if (method_name == "springs") method = limber::Method::springs;
  else if (method_name == "lagrange") method = limber::Method::lagrange;
  else if (method_name == "featherstone") method = limber::Method::featherstone;
  else if (method_name != "particles") {
    std::fprintf(stderr, "ragdoll: unknown method '%s' (particles, springs, lagrange or featherstone)\n", method_name.c_str());
    return 2;
  }
  // The scene and the settings it gives the methods (its relaxation sweeps, for one).
  limber::World world(limber::load_scene_text(limber::embedded_humanoid_scene(), "humanoid"), method);

  // Frames of 1/60 s, each as four of the scene's steps of 1/240 s (the stiff springs need them).
  const double dt = 1.0 / 60;
  const int steps_per_frame = static_cast<int>(std::lround(dt / world.model().settings.time_step));
  for (int frame = 1; frame <= 180; ++frame) {
    if (frame == 60) {  // a blow to the head, from the side
      const limber::BodyId head = world.body("head");
      world.apply_impulse(head, {0, 8, 0}, world.pose(head).position);
    }
    if (frame == 90) world.apply_torque(world.body("basin"), {0, 0, 40});  // a twist, N·m over one step
    for (int k = 0; k < steps_per_frame; ++k) {
      if (world.step() != limber::StepStatus::ok) {
        std::fprintf(stderr, "ragdoll: diverged at frame %d\n", frame);
        return 1;
      }
    }
    if (frame % 30 != 0) continue;
    std::printf("t %.2f s\n", frame * dt);
    for (const limber::BodyId body : world.bodies()) {
      const limber::Pose pose = world.pose(body);
      std::printf("  %-16s (%6.3f, %6.3f, %6.3f)  q (%6.3f, %6.3f, %6.3f, %6.3f)\n", world.body_description(body).name.c_str(),
                  pose.position.x(), pose.position.y(), pose.position.z(), pose.orientation.w(), pose.orientation.x(),
                  pose.orientation.y(), pose.orientation.z());
    }
  }
  return 0;
}
