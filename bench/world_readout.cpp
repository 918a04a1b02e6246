// The C++ side of the Python race (bench/python_overhead.py): a World stepped S times from the
// scene's initial state, every pose read out after each step (World::step, then World::poses into
// one buffer), the particle method with the scene's settings on one thread. Prints the loop's
// wall time in seconds, nothing else, so the Python script alternates it with its own loop.
//   build/bench/world_readout SCENE STEPS [LINKS]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: world_readout SCENE STEPS [LINKS]\n");
    return 2;
  }
  try {
    limber::SceneOptions options;
    if (argc == 4) options.links = std::stol(argv[3]);
    const limber::Scene scene = limber::load_scene_file(argv[1], options);
    limber::World world(scene, limber::Method::particles);
    std::vector<limber::Pose> poses(world.bodies().size());
    const long steps = std::stol(argv[2]);
    const auto start = std::chrono::steady_clock::now();
    for (long n = 0; n < steps; ++n) {
      world.step();
      world.poses(poses);
    }
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    std::printf("%.9f\n", elapsed.count());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "world_readout: %s\n", error.what());
    return 1;
  }
  return 0;
}
