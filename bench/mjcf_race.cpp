// MuJoCo's own models under MuJoCo 2.2.2 (mj_step) and under limber (load_scene_file of the same
// .xml, stepped through the World) in one run: load time, steps per second, time per humanoid
// per 1/60 s, the largest joint gap, the deepest penetration and the energy over the fall
// (bench/speed.md, "MuJoCo's models").
//
//   build/bench/mjcf_race [MODEL.xml ...] [--seconds S] [--rounds R] [--method M [--threads N] ...]
//                         [--integrator semi-implicit|rk4]
//
// MODEL defaults to MuJoCo's humanoid.xml and 22_humanoids.xml (libmujoco-samples). Each round
// runs every engine from the file's initial state for S simulated seconds (default 5), one engine
// after the other, so a busy machine slows them alike; a row gives the median over R rounds
// (default 3) of the stepping thread's CPU time (of the wall time, for a method on 2 threads,
// whose helper thread works too). limber runs with the import's settings
// (scene.methods: the particles' joint trees, 2 substeps of 2 sweeps). The measures come from
// the first round:
// - joint gap: limber's observer (relative to the limbs' length); MuJoCo's joints are its
//   coordinates, closed by construction;
// - penetration: MuJoCo's deepest contact (−dist), limber's deepest overlap of its limbs with
//   each other and the ground (the CLI's measure);
// - energy: each engine's own, at the start and the end: MuJoCo's potential (gravity and joint
//   springs) plus kinetic; limber's gravity plus kinetic (its observers leave out the springs);
// - the floor: at the end, the lowest point of each free box and ellipsoid within 1 cm of the
//   floor (z = 0) or below it, the same measure in both engines (the support along −z of the
//   shape as placed): the range over those objects, mm, and how many. Where a shape rests as
//   itself its lowest point is at the floor (MuJoCo's a little below: its soft contacts).
// Method M is any method that can run the model, on N threads (default 1; default methods:
// particles and featherstone, each on 1 and 2 threads). --integrator sets Featherstone's (RK4 by default; semi-implicit Euler is
// MuJoCo's default, the integrator it races with here).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bench/thread_time.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {
namespace {

struct Measures {
  double cpu_seconds = 0;
  double largest_gap = 0, deepest_penetration = 0;
  double energy_start = 0, energy_end = 0;
  double floor_lowest = 0, floor_highest = 0;  // m: the range of the floor objects' lowest points
  int floor_objects = 0;
};

// An object within this of the floor is on it, m.
constexpr double kOnTheFloor = 0.01;

// Adds a box's or ellipsoid's lowest point z (m) to the floor range when it is on the floor.
void add_floor_object(Measures& out, double lowest) {
  if (!(lowest < kOnTheFloor)) return;
  out.floor_lowest = out.floor_objects == 0 ? lowest : std::min(out.floor_lowest, lowest);
  out.floor_highest = out.floor_objects == 0 ? lowest : std::max(out.floor_highest, lowest);
  ++out.floor_objects;
}

// How far below its centre a box or an ellipsoid of half-extents h reaches, its axes' world z
// components `up` (row 2 of its rotation): Σ|up_k|·h_k for a box, |up ∘ h| for an ellipsoid.
double reach_down(bool is_box, const Eigen::Vector3d& up, const Eigen::Vector3d& h) {
  return is_box ? up.cwiseAbs().dot(h) : up.cwiseProduct(h).norm();
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// The best of five loads, s.
template <typename Load>
double load_seconds(Load load) {
  double best = 1e30;
  for (int k = 0; k < 5; ++k) {
    const auto start = std::chrono::steady_clock::now();
    load();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

Measures run_mujoco(const mjModel* model, mjData* data, long steps, bool measure) {
  mj_resetData(model, data);
  Measures out;
  const auto energy = [&] {
    mj_energyPos(model, data), mj_energyVel(model, data);
    return data->energy[0] + data->energy[1];
  };
  if (measure) mj_forward(model, data), out.energy_start = energy();
  const double start = thread_seconds();
  for (long n = 0; n < steps; ++n) {
    mj_step(model, data);
    if (!measure) continue;
    out.cpu_seconds -= thread_seconds();
    for (int c = 0; c < data->ncon; ++c) out.deepest_penetration = std::max(out.deepest_penetration, -data->contact[c].dist);
    out.cpu_seconds += thread_seconds();
  }
  out.cpu_seconds += thread_seconds() - start;
  if (measure) out.energy_end = energy();
  for (int g = 0; g < model->ngeom && measure; ++g) {
    const int type = model->geom_type[g], body = model->geom_bodyid[g];
    if (type != mjGEOM_BOX && type != mjGEOM_ELLIPSOID) continue;
    const int joint = model->body_jntadr[body];
    if (joint < 0 || model->jnt_type[joint] != mjJNT_FREE) continue;
    const mjtNum* xmat = data->geom_xmat + 9 * g;  // row-major: row 2 is the world z of the geom's axes
    const Eigen::Vector3d up(xmat[6], xmat[7], xmat[8]), h(model->geom_size[3 * g], model->geom_size[3 * g + 1], model->geom_size[3 * g + 2]);
    add_floor_object(out, data->geom_xpos[3 * g + 2] - reach_down(type == mjGEOM_BOX, up, h));
  }
  return out;
}

// A limber method on `threads` threads (the particles' only).
struct Runner {
  Method method = Method::particles;
  int threads = 1;
  std::optional<Integrator> integrator;  ///< Featherstone's, when not its default
};

// The stepping thread's CPU time, s; the wall time when helper threads work too.
double clock_seconds(int threads) {
  if (threads == 1) return thread_seconds();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

Measures run_limber(const Scene& scene, Runner runner, long steps, bool measure) {
  WorldOptions options = world_options(runner.method, scene.methods);
  options.particles.threads = runner.threads;
  options.featherstone.threads = runner.threads;
  if (runner.integrator) options.featherstone.integrator = *runner.integrator;
  World world(scene.model, options);
  Measures out;
  if (measure) out.energy_start = world.observe().energy();
  double stepping = 0;
  for (long n = 0; n < steps; ++n) {
    const double start = clock_seconds(runner.threads);
    if (world.step(scene.model.settings.time_step) != StepStatus::ok) throw std::runtime_error("limber: the step failed");
    stepping += clock_seconds(runner.threads) - start;
    if (!measure) continue;
    out.largest_gap = std::max(out.largest_gap, world.observe().max_joint_gap);
    out.deepest_penetration = std::max(out.deepest_penetration, world.observe().penetration.depth);
  }
  out.cpu_seconds = stepping;
  if (measure) out.energy_end = world.observe().energy();
  std::vector<Pose> poses(scene.model.bodies.size());
  world.poses(poses);
  for (std::size_t b = 0; b < poses.size() && measure; ++b) {
    const Shape& shape = scene.model.bodies[b].shape;
    if (!has_half_extents(shape)) continue;
    const Eigen::Vector3d up = (poses[b].orientation * shape.rotation).toRotationMatrix().row(2).transpose();
    add_floor_object(out, poses[b].position.z() - reach_down(shape.type == ShapeType::box, up, shape.half_extents));
  }
  return out;
}

void print_row(const char* engine, double load, const std::vector<double>& times, const Measures& first, long steps, double dt, int humanoids) {
  const double per_step = median(times) / static_cast<double>(steps);
  const double per_humanoid_frame = per_step * (1.0 / 60.0 / dt) / humanoids;
  char floor[64] = "none";
  if (first.floor_objects > 0) std::snprintf(floor, sizeof floor, "%.2f … %.2f (%d)", 1e3 * first.floor_lowest, 1e3 * first.floor_highest, first.floor_objects);
  std::printf("| %-26s | %8.1f | %9.0f | %10.0f | %9.2g | %9.3g | %8.1f → %-8.1f | %s |\n", engine, 1e3 * load, 1.0 / per_step,
              1e6 * per_humanoid_frame, first.largest_gap, first.deepest_penetration, first.energy_start, first.energy_end, floor);
}

void race(const std::filesystem::path& file, double seconds, int rounds, const std::vector<Runner>& methods) {
  char error[1000] = "";
  mjModel* model = mj_loadXML(file.c_str(), nullptr, error, sizeof error);
  if (!model) throw std::runtime_error(file.string() + ": mj_loadXML: " + error);
  model->opt.enableflags |= mjENBL_ENERGY;
  mjData* data = mj_makeData(model);
  const Scene scene = load_scene_file(file);
  const double dt = model->opt.timestep;
  const long steps = std::lround(seconds / dt);
  int humanoids = 0;
  for (int j = 0; j < model->njnt; ++j) humanoids += model->jnt_type[j] == mjJNT_FREE ? 1 : 0;
  humanoids = std::max(humanoids, 1);
  const double mujoco_load = load_seconds([&] {
    char e[1000] = "";
    mj_deleteModel(mj_loadXML(file.c_str(), nullptr, e, sizeof e));
  });
  const double limber_load = load_seconds([&] { (void)load_scene_file(file); });

  std::vector<double> mujoco_times;
  std::vector<std::vector<double>> limber_times(methods.size());
  Measures mujoco_first;
  std::vector<Measures> limber_first(methods.size());
  for (int round = 0; round < rounds; ++round) {
    const Measures m = run_mujoco(model, data, steps, round == 0);
    mujoco_times.push_back(m.cpu_seconds);
    if (round == 0) mujoco_first = m;
    for (std::size_t k = 0; k < methods.size(); ++k) {
      const Measures l = run_limber(scene, methods[k], steps, round == 0);
      limber_times[k].push_back(l.cpu_seconds);
      if (round == 0) limber_first[k] = l;
    }
  }
  std::printf("\n%s: %d humanoid(s), %ld steps of %g s, median of %d rounds (thread CPU time)\n\n", file.filename().c_str(), humanoids, steps,
              dt, rounds);
  std::printf("| engine                     | load ms  | steps/s   | µs/humanoid/frame | joint gap | penetr. m | energy J start → end | floor objects' lowest points, mm (count) |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---|---|\n");
  print_row("MuJoCo 2.2.2 mj_step", mujoco_load, mujoco_times, mujoco_first, steps, dt, humanoids);
  for (std::size_t k = 0; k < methods.size(); ++k) {
    std::string name = "limber " + std::string(method_name(methods[k].method)) + ", " + std::to_string(methods[k].threads) +
                       (methods[k].threads == 1 ? " thread" : " threads");
    if (methods[k].integrator && methods[k].method == Method::featherstone) name += std::string(", ") + integrator_name(*methods[k].integrator);
    print_row(name.c_str(), limber_load, limber_times[k], limber_first[k], steps, dt, humanoids);
  }
  mj_deleteData(data);
  mj_deleteModel(model);
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  using namespace limber;
  std::vector<std::filesystem::path> files;
  std::vector<Runner> methods;
  double seconds = 5;
  int rounds = 3;
  std::optional<Integrator> integrator;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string argument = argv[i];
      if (argument == "--seconds" && i + 1 < argc) {
        seconds = std::stod(argv[++i]);
      } else if (argument == "--rounds" && i + 1 < argc) {
        rounds = std::max(1, std::stoi(argv[++i]));
      } else if (argument == "--method" && i + 1 < argc) {
        const std::string name = argv[++i];
        bool known = false;
        for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
          if (method_name(method) == name) methods.push_back({method, 1, std::nullopt}), known = true;
        }
        if (!known) throw std::invalid_argument("unknown method " + name + " (particles, springs, lagrange or featherstone)");
      } else if (argument == "--threads" && i + 1 < argc) {
        if (methods.empty()) throw std::invalid_argument("--threads: follows the --method it applies to");
        methods.back().threads = std::stoi(argv[++i]);
        if (methods.back().threads < 1 || methods.back().threads > kMaxThreads) throw std::invalid_argument("--threads: must be in [1, 256]");
      } else if (argument == "--integrator" && i + 1 < argc) {
        const std::string name = argv[++i];
        if (name == "semi-implicit") {
          integrator = Integrator::semi_implicit_euler;
        } else if (name == "rk4") {
          integrator = Integrator::rk4;
        } else {
          throw std::invalid_argument("unknown integrator " + name + " (semi-implicit or rk4)");
        }
      } else {
        files.emplace_back(argument);
      }
    }
    if (methods.empty()) {
      methods = {{Method::particles, 1, std::nullopt}, {Method::particles, 2, std::nullopt}, {Method::featherstone, 1, std::nullopt},
                 {Method::featherstone, 2, std::nullopt}};
    }
    for (Runner& runner : methods) runner.integrator = integrator;
    if (files.empty()) files = {"/usr/share/mujoco/model/humanoid/humanoid.xml", "/usr/share/mujoco/model/humanoid/22_humanoids.xml"};
    for (const auto& file : files) race(file, seconds, rounds, methods);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "mjcf_race: %s\n", error.what());
    return 1;
  }
  return 0;
}
