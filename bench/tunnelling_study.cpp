// Tunnelling: the highest speed at which the thesis's ball (radius 0.05 m, 2.27 kg, restitution
// 0.8) still hits a free limb 4 cm thick (a capsule of radius 0.02 m, 0.4 m long, 1 kg), and
// still bounces off a static plate 2 cm thick (a box, 1 m square), under every method, at
// Δt = 1/60 s and 1/240 s (bench/collision.md, "Collision: contact sweeps, the cost of collision,
// tunnelling").
//
//   build/bench/tunnelling_study            the tables (a few seconds)
//   build/bench/tunnelling_study --detail   also each listed speed: the starts that hit, the least momentum passed
//
// The limb stands along z at the origin (the plate across x, its faces at x = ±0.01 m, with the
// limb 3 m aside), gravity off, no ground; the ball flies along +x at the target's middle. A hit
// on the limb: the limb leaves with momentum along +x of at least 10⁻³ of the ball's. A hit on
// the plate: the ball ends on its own side (its centre at x < 0), 1 m of flight after it would
// have passed. Where a method detects contacts only at the end of each step, whether the ball is
// caught depends on where the step boundaries fall along its path; so each speed is run from
// kPhases starts spread over one step's travel (the ball's centre 0.5 m + (j / kPhases)·v·Δt
// before the target's middle), and a speed counts as hit only when every start hits. Speeds
// 1 … 1000 m/s from a list, then bisection between the highest listed speed that hits from every
// start and the next listed one, to 1%.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <variant>
#include <vector>

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/world/world.hpp"

namespace {

using namespace limber;

constexpr int kPhases = 8;
constexpr double kLimbRadius = 0.02, kLimbLength = 0.4, kLimbMass = 1.0;
constexpr double kBallRadius = 0.05, kBallMass = 2.26796185, kBallRestitution = 0.8;  // humanoid.json's ball
constexpr double kPlateHalfThickness = 0.01, kPlateHalfSide = 0.5;  // m
constexpr double kStartGap = 0.5;  // m, from the ball's centre to the target's middle at phase 0

enum class Target { limb, plate };

Model target(Target kind, double speed, double start_distance) {
  Model model;
  model.name = "tunnelling";
  model.settings.gravity = Vector3::Zero();
  model.settings.sleep.enabled = false;
  model.settings.divergence_speed = 1e5;  // the default 1000 m/s would call the fastest ball a divergence
  Body limb;
  limb.name = "limb";
  limb.shape = {ShapeType::capsule, kLimbLength, kLimbRadius};
  limb.mass = kLimbMass;
  limb.position = kind == Target::limb ? Vector3::Zero() : Vector3(0, 3, 0);
  limb.axis = Vector3::UnitZ();
  model.bodies.push_back(limb);
  if (kind == Target::plate) {
    StaticCollider plate;
    plate.name = "plate";
    plate.type = ColliderType::box;
    plate.half_extents = Vector3(kPlateHalfThickness, kPlateHalfSide, kPlateHalfSide);
    model.colliders.push_back(plate);
  }
  model.balls = {Ball{.radius = kBallRadius, .mass = kBallMass, .restitution = kBallRestitution,
                     .position = Vector3(-start_distance, 0, 0), .velocity = Vector3(speed, 0, 0)}};
  return model;
}

// The ball's centre now, whatever the method (the last of the limb segments).
Vector3 ball_centre(const World& world) {
  std::vector<LimbSegment> segments;
  world.segments(segments);
  return segments.back().head;
}

struct Shot {
  bool hit = false;
  bool diverged = false;
  double transfer = 0;  // the limb's momentum along +x / the ball's initial momentum (plate: 0)
};

// One ball at `speed` from `start_distance`, stepped until it is 1 m past the target (had it flown on).
Shot shoot(Target kind, Method method, double dt, double speed, double start_distance) {
  WorldOptions options;
  options.method = method;
  World world(target(kind, speed, start_distance), options);
  const BodyId limb = world.body("limb");
  const int steps = std::max(4, static_cast<int>(std::ceil((start_distance + 1.0) / (speed * dt))) + 1);
  Shot shot;
  for (int k = 0; k < steps; ++k) {
    if (world.step(dt) != StepStatus::ok) {
      shot.diverged = true;
      return shot;
    }
  }
  if (kind == Target::plate) {
    shot.hit = ball_centre(world).x() < 0;
    return shot;
  }
  shot.transfer = kLimbMass * world.motion(limb).linear.x() / (kBallMass * speed);
  shot.hit = shot.transfer > 1e-3;
  return shot;
}

struct Volley {
  int hits = 0, diverged = 0;
  double least_transfer = 1e300;
};

Volley volley(Target kind, Method method, double dt, double speed) {
  Volley v;
  for (int j = 0; j < kPhases; ++j) {
    const Shot shot = shoot(kind, method, dt, speed, kStartGap + (double(j) / kPhases) * speed * dt);
    v.hits += shot.hit ? 1 : 0;
    v.diverged += shot.diverged ? 1 : 0;
    if (!shot.diverged) v.least_transfer = std::min(v.least_transfer, shot.transfer);
  }
  return v;
}

struct Row {
  Target target = Target::limb;
  Method method = Method::particles;
  const char* dt_name = "";
  double highest = 0;     // bisected: every start hits
  double first_miss = 0;  // the listed speed where some start misses (0: none)
  double above = 0;       // a listed speed above first_miss where every start hits again (0: none)
  std::string misses;     // at first_miss: starts that hit
};

const char* target_name(Target kind) { return kind == Target::limb ? "limb" : "plate"; }

// One row of the table: every listed speed, then the bisection; with `detail`, the listed volleys.
Row measure(Target kind, Method method, const char* dt_name, double dt, const std::vector<double>& speeds, bool detail) {
  Row row;
  row.target = kind, row.method = method, row.dt_name = dt_name;
  std::vector<Volley> listed;
  for (double s : speeds) listed.push_back(volley(kind, method, dt, s));
  if (detail) {
    std::printf("%-6s %-13s %-6s", target_name(kind), std::string(method_name(method)).c_str(), dt_name);
    for (const Volley& v : listed) {
      char cell[16];
      std::snprintf(cell, sizeof cell, v.diverged ? "%d/%dd" : "%d", v.hits, v.diverged);
      std::printf(" %8s", cell);
    }
    if (kind == Target::limb) {
      std::printf("\n%-6s %-13s %-6s", "", "", "");
      for (const Volley& v : listed) {
        if (v.least_transfer > 1e299) std::printf(" %8s", "-");
        else std::printf(" %8.3f", v.least_transfer);
      }
      std::printf("   (least momentum transfer, limb / ball)");
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  const auto all_hit = [&](const Volley& v) { return v.hits == kPhases; };
  std::size_t k = 0;
  while (k < speeds.size() && all_hit(listed[k])) ++k;
  if (k == speeds.size()) {
    row.highest = speeds.back();
    return row;
  }
  row.first_miss = speeds[k];
  row.misses = std::to_string(listed[k].hits) + "/" + std::to_string(kPhases);
  for (std::size_t m = k + 1; m < speeds.size(); ++m) {
    if (all_hit(listed[m])) row.above = speeds[m];
  }
  double low = k == 0 ? 0 : speeds[k - 1], high = speeds[k];
  while (low > 0 && high - low > 0.01 * low) {
    const double middle = 0.5 * (low + high);
    (all_hit(volley(kind, method, dt, middle)) ? low : high) = middle;
  }
  row.highest = low;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const bool detail = argc > 1 && std::strcmp(argv[1], "--detail") == 0;
  const std::vector<double> speeds = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000};
  const std::vector<std::pair<const char*, double>> steps = {{"1/60", 1.0 / 60}, {"1/240", 1.0 / 240}};
  const Method methods[] = {Method::particles, Method::springs, Method::lagrange, Method::featherstone};
  std::printf("# ball r = %.2f m, %.2f kg, e = %.1f; limb: capsule r = %.2f m, L = %.1f m, %.1f kg, free; plate: static box "
              "%.2f m thick, %.1f m square; no gravity; %d start phases per speed; hit = limb momentum along the ball's path "
              "> 1e-3 of the ball's, or the ball ends on its side of the plate\n",
              kBallRadius, kBallMass, kBallRestitution, kLimbRadius, kLimbLength, kLimbMass, 2 * kPlateHalfThickness,
              2 * kPlateHalfSide, kPhases);
  if (detail) {
    std::printf("%-6s %-13s %-6s", "target", "method", "dt");
    for (double s : speeds) std::printf(" %8.0f", s);
    std::printf("   (starts that hit, of %d; d: diverged)\n", kPhases);
  }
  std::vector<Row> rows;
  for (const Target kind : {Target::limb, Target::plate}) {
    for (const Method method : methods) {
      for (const auto& [dt_name, dt] : steps) rows.push_back(measure(kind, method, dt_name, dt, speeds, detail));
    }
  }
  std::printf("\n%-6s %-13s %-6s %26s %24s %14s\n", "target", "method", "dt", "highest hit, all starts", "first listed miss",
              "hits again at");
  for (const Row& row : rows) {
    char highest[32], miss[40], again[24];
    std::snprintf(highest, sizeof highest, row.first_miss == 0 ? ">= %.0f m/s" : "%.3g m/s", row.highest);
    if (row.first_miss == 0) {
      std::snprintf(miss, sizeof miss, "-");
    } else {
      std::snprintf(miss, sizeof miss, "%.0f m/s (%s hit)", row.first_miss, row.misses.c_str());
    }
    std::snprintf(again, sizeof again, row.above > 0 ? "%.0f m/s" : "-", row.above);
    std::printf("%-6s %-13s %-6s %26s %24s %14s\n", target_name(row.target), std::string(method_name(row.method)).c_str(),
                row.dt_name, highest, miss, again);
  }
  return 0;
}
