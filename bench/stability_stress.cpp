// Stability stress of every method (bench/reliability.md, "Stability stress"). One Model, nine
// Methods (kernel/study/simulation.hpp), every run classified by study::classify() as stable or
// diverged — non-finite (NaN, or a point faster than Settings::divergence_speed), energy growth
// (a gain beyond StabilityBounds::energy_gain × energy_scale(), i.e. half the chain's
// weight × length) or joint gap (a joint or link beyond half a link length). A run stops at the
// first divergence.
//
//   grid     the chain of 10 links of 0.1 m and 1 kg, pinned, released horizontally, undamped,
//            with its end link end_mass_ratio × as heavy (10⁻⁴ … 10⁴: a light end, equal links,
//            a heavy end), at Δt = 1/1000 … 1/15 s, 10 s each;
//   long     10⁶ steps of the equal-mass chain at Δt = 1/240 s (69 min simulated) per method:
//            energy drift and largest gap over the whole run;
//   impacts  the humanoid (tools/scenes/humanoid.json) hit by the ball at 10 … 100 m/s;
//   springs  the eq. 3.15 check: explicit springs' predicted stability boundary against the
//            measured one, over stiffness × Δt (kernel/study/spring_stability.hpp derives the bound).
//
// Usage: stability_stress grid|long|impacts|springs [--quick] [--csv FILE]
// Tables go to stdout, one CSV row per run to FILE. --quick is the CI form: seconds, not minutes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/study/spring_stability.hpp"

namespace {

using namespace limber;
using namespace limber::study;

// ---------------------------------------------------------------------------------------------
// The methods and the chain.

// The default spring (SpringSettings, a scene's "springs"): k = 2·10⁴ N/m, c = 20 N·s/m.
constexpr double kSceneStiffness = 2e4, kSceneDamping = 20;

study::Method spring_method(std::string series, Integrator integrator, double stiffness, double damping, double dt) {
  return {.series = std::move(series), .setting = "k " + std::to_string(static_cast<long>(stiffness)) + " N/m",
          .family = Family::springs, .time_step = dt,
          .springs = {.integrator = integrator, .stiffness = stiffness, .damping = damping, .newton_iterations = 2}};
}

// One Method per series the issue names, at time step `dt`. Verlet runs one thread: the runs are
// small and the machine is shared.
std::vector<study::Method> stress_methods(double dt) {
  return {
      {.series = "verlet gauss-seidel", .setting = "20 sweeps", .family = Family::particles, .time_step = dt,
       .verlet = {.threads = 1}, .sweeps = 20},
      {.series = "verlet direct", .setting = "2 Newton steps", .family = Family::particles, .time_step = dt,
       .verlet = {.solver = RelaxationSolver::direct, .threads = 1, .newton_iterations = 2}},
      spring_method("springs semi-implicit euler", Integrator::semi_implicit_euler, kSceneStiffness, kSceneDamping, dt),
      spring_method("springs forward euler", Integrator::euler, kSceneStiffness, kSceneDamping, dt),
      spring_method("springs backward euler", Integrator::backward_euler, kSceneStiffness, kSceneDamping, dt),
      {.series = "lagrange baumgarte", .setting = "semi-implicit euler", .family = Family::lagrange, .time_step = dt,
       .lagrange = {.integrator = Integrator::semi_implicit_euler, .stabilization = Stabilization::baumgarte}},
      {.series = "lagrange projection", .setting = "semi-implicit euler", .family = Family::lagrange, .time_step = dt,
       .lagrange = {.integrator = Integrator::semi_implicit_euler, .stabilization = Stabilization::projection}},
      {.series = "featherstone rk4", .setting = "", .family = Family::featherstone, .time_step = dt,
       .featherstone = {.integrator = Integrator::rk4}},
      {.series = "featherstone semi-implicit euler", .setting = "", .family = Family::featherstone, .time_step = dt,
       .featherstone = {.integrator = Integrator::semi_implicit_euler}},
  };
}

// The stress chain: `links` links of 0.1 m and 1 kg, the last end_mass_ratio kg, pinned at the
// origin and laid out horizontally along +x, so it is released to swing down. No damping.
Model stress_chain(double end_mass_ratio, std::size_t links = 10) {
  return make_chain_model({.links = links, .link_length = 0.1, .link_mass = 1, .end_mass_ratio = end_mass_ratio});
}

// The stated bounds (run_metrics.hpp's defaults): gain > 0.5 × m·g·ΣL, gap > 0.5 of a link.
const StabilityBounds kBounds{};

bool diverged(const RunErrors& errors) { return classify(errors, kBounds) != Stability::stable; }

// The eq. 3.15 check asks about the integrator's stability alone: a spring too weak to hold the
// chain opens its joints (gap) without blowing up, so there only non-finite states and energy
// growth count.
bool blew_up(const RunErrors& errors) {
  const Stability stability = classify(errors, {.energy_gain = kBounds.energy_gain, .joint_gap = std::numeric_limits<double>::infinity()});
  return stability != Stability::stable;
}

// ---------------------------------------------------------------------------------------------
// Output.

struct Output {
  std::optional<std::ofstream> csv;
  void header(const char* columns) {
    if (csv) *csv << columns << '\n';
  }
  template <typename... Arguments>
  void row(const char* format, Arguments... arguments) {
    if (!csv) return;
    char line[512];
    std::snprintf(line, sizeof line, format, arguments...);
    *csv << line << '\n';
  }
};

double wall_seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One letter per outcome in the printed maps.
char letter(Stability stability) {
  switch (stability) {
    case Stability::stable: return '.';
    case Stability::non_finite: return 'N';
    case Stability::energy_growth: return 'E';
    case Stability::joint_gap: return 'G';
  }
  return '?';
}

std::string time_step_name(double dt) {
  char text[32];
  std::snprintf(text, sizeof text, "1/%.0f", 1 / dt);
  return text;
}

void print_bounds(double duration) {
  std::printf("# diverged: non-finite state or a point faster than %g m/s; energy gain > %g x m*g*sum(L);"
              " joint gap or link stretch > %g of a link. Runs of %g s stop at the first divergence.\n",
              Settings{}.divergence_speed, kBounds.energy_gain, kBounds.joint_gap, duration);
}

// ---------------------------------------------------------------------------------------------
// grid: mass ratio × Δt per method.

void grid(bool quick, Output& out) {
  const std::vector<double> ratios = quick ? std::vector<double>{1e-4, 1, 1e4}
                                           : std::vector<double>{1e-4, 1e-3, 1e-2, 0.1, 1, 10, 100, 1e3, 1e4};
  const std::vector<double> steps = quick ? std::vector<double>{1.0 / 1000, 1.0 / 240, 1.0 / 60, 1.0 / 15}
                                          : std::vector<double>{1.0 / 1000, 1.0 / 480, 1.0 / 240, 1.0 / 120,
                                                                1.0 / 60, 1.0 / 30, 1.0 / 15};
  const double duration = quick ? 2 : 10;
  print_bounds(duration);
  std::printf("# chain: 10 links x 0.1 m x 1 kg, end link mass_ratio kg, pinned, released horizontally, undamped\n");
  std::printf("# map: rows dt, columns mass ratio; . stable, N non-finite, E energy growth, G joint gap\n");
  out.header("section,method,setting,mass_ratio,dt,duration,steps,stability,max_gap,energy_gain,energy_drift,wall_s,predicted_stable_dt");

  const std::size_t method_count = stress_methods(1.0 / 240).size();
  for (std::size_t m = 0; m < method_count; ++m) {
    const study::Method named = stress_methods(1.0 / 240)[m];
    std::printf("\n%s %s\n%8s", named.series.c_str(), named.setting.c_str(), "dt\\ratio");
    for (const double ratio : ratios) std::printf(" %6g", ratio);
    std::printf("\n");
    // The explicit springs' predicted boundary per mass ratio (see above).
    std::vector<double> predicted(ratios.size(), std::numeric_limits<double>::quiet_NaN());
    if (named.family == Family::springs && named.springs.integrator != Integrator::backward_euler) {
      for (std::size_t r = 0; r < ratios.size(); ++r) {
        predicted[r] = predicted_largest_stable_step(named.springs.integrator, spring_mode_frequencies(stress_chain(ratios[r]), kSceneStiffness),
                                                     kSceneStiffness, kSceneDamping);
      }
    }
    for (auto dt = steps.rbegin(); dt != steps.rend(); ++dt) {
      std::printf("%8s", time_step_name(*dt).c_str());
      for (std::size_t r = 0; r < ratios.size(); ++r) {
        const study::Method method = stress_methods(*dt)[m];
        const auto start = std::chrono::steady_clock::now();
        Simulation simulation(stress_chain(ratios[r]), method);
        const RunErrors errors = observe_run(simulation, duration, 0, diverged).errors;
        const Stability stability = classify(errors, kBounds);
        std::printf("      %c", letter(stability));
        out.row("grid,%s,%s,%g,%.9g,%g,%ld,%s,%.6g,%.6g,%.6g,%.4g,%.6g", method.series.c_str(), method.setting.c_str(), ratios[r], *dt,
                duration, errors.steps, name(stability), std::max(errors.max_joint_gap, errors.max_link_stretch),
                errors.relative_energy_gain(), errors.relative_energy_drift(), wall_seconds_since(start), predicted[r]);
      }
      std::printf("\n");
      std::fflush(stdout);
    }
    if (!std::isnan(predicted.front())) {
      std::printf("%8s", "eq3.15");
      for (const double bound : predicted) std::printf(" %6s", time_step_name(bound).c_str());
      std::printf("   <- predicted largest stable dt (k = %g N/m, c = %g N s/m)\n", kSceneStiffness, kSceneDamping);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// long: 10⁶ steps per method.

void long_runs(bool quick, Output& out) {
  const double dt = 1.0 / 240;
  const long steps = quick ? 10'000 : 1'000'000;
  print_bounds(steps * dt);
  std::printf("# %ld steps of dt = 1/240 s (%.0f s simulated) unless the setting says otherwise, the equal-mass 10-link chain"
              " released horizontally, undamped; drift = max |E - E0|, gain = max (E - E0), both / m*g*sum(L)\n",
              steps, steps * dt);
  std::printf("%-34s %-26s %10s %-14s %12s %12s %12s %9s\n", "method", "setting", "steps", "outcome", "max gap/L",
              "drift/scale", "gain/scale", "wall s");
  out.header("section,method,setting,dt,steps_asked,steps,stability,max_gap,rms_gap,energy_drift,energy_gain,energy_scale_J,wall_s");
  // Every method at 1/240 s, then the explicit ones that diverge there again at a step inside
  // their bound (springs: eq. 3.15 above; Featherstone's semi-implicit Euler: the grid's).
  std::vector<study::Method> methods = stress_methods(dt);
  methods.push_back(spring_method("springs semi-implicit euler", Integrator::semi_implicit_euler, kSceneStiffness, kSceneDamping, 1.0 / 480));
  methods.push_back(spring_method("springs forward euler", Integrator::euler, kSceneStiffness, kSceneDamping, 1.0 / 2000));
  methods.push_back(stress_methods(1.0 / 1000).back());
  for (study::Method& method : methods) {
    if (method.time_step != dt) method.setting += (method.setting.empty() ? "dt " : ", dt ") + time_step_name(method.time_step);
  }
  for (const study::Method& method : methods) {
    const auto start = std::chrono::steady_clock::now();
    Simulation simulation(stress_chain(1), method);
    const RunErrors errors = observe_run(simulation, steps * method.time_step, 0, diverged).errors;
    const Stability stability = classify(errors, kBounds);
    const double wall = wall_seconds_since(start);
    const double gap = std::max(errors.max_joint_gap, errors.max_link_stretch);
    std::printf("%-34s %-26s %10ld %-14s %12.3g %12.3g %12.3g %9.1f\n", method.series.c_str(), method.setting.c_str(), errors.steps,
                name(stability), gap, errors.relative_energy_drift(), errors.relative_energy_gain(), wall);
    std::fflush(stdout);
    out.row("long,%s,%s,%.9g,%ld,%ld,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g", method.series.c_str(), method.setting.c_str(), method.time_step, steps,
            errors.steps, name(stability), gap, errors.rms_joint_gap, errors.relative_energy_drift(), errors.relative_energy_gain(),
            errors.energy_scale, wall);
  }
}

// ---------------------------------------------------------------------------------------------
// impacts: the humanoid and the ball.

void impacts(bool quick, Output& out) {
  const Model scene = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/humanoid.json").model;
  const std::vector<double> speeds = quick ? std::vector<double>{10, 100} : std::vector<double>{10, 20, 50, 100};
  const double dt = scene.settings.time_step, duration = quick ? 1 : 3;
  print_bounds(duration);
  std::printf("# the humanoid (medium body) hit by the %.2f kg ball, dt = 1/%.0f s; the energy bound is taken against"
              " m*g*sum(L) + the ball's kinetic energy; knock: how far the body's centre of mass moved horizontally (m)\n",
              scene.balls.front().mass, 1 / dt);
  std::printf("%-34s %-18s", "method", "setting");
  for (const double speed : speeds) std::printf(" %20s", (std::to_string(static_cast<int>(speed)) + " m/s").c_str());
  std::printf("\n");
  out.header("section,method,setting,ball_speed,dt,duration,steps,stability,max_gap,energy_gain,energy_drift,energy_scale_J,knock_m");
  for (const study::Method& method : stress_methods(dt)) {
    std::printf("%-34s %-18s", method.series.c_str(), method.setting.c_str());
    for (const double speed : speeds) {
      Model model = scene;
      model.balls.front().velocity = speed * model.balls.front().velocity.normalized();
      Simulation simulation(model, method);
      const Eigen::Vector3d start = simulation.observe().body_centre_of_mass;
      // A diverging step ends the run; energy is judged at the end against the whole scene's
      // energy (the ball brings ½ m v², up to 11 kJ at 100 m/s).
      RunErrors errors = observe_run(simulation, duration).errors;
      errors.energy_scale += 0.5 * model.balls.front().mass * speed * speed;
      const Stability stability = classify(errors, kBounds);
      const double knock = (simulation.observe().body_centre_of_mass - start).head<2>().norm();
      const double gap = std::max(errors.max_joint_gap, errors.max_link_stretch);
      char cell[64];
      std::snprintf(cell, sizeof cell, "%s %.2g/%.2gm", stability == Stability::stable ? "ok" : name(stability), gap,
                    std::isfinite(knock) ? knock : -1.0);
      std::printf(" %20s", cell);
      std::fflush(stdout);
      out.row("impacts,%s,%s,%g,%.9g,%g,%ld,%s,%.6g,%.6g,%.6g,%.6g,%.6g", method.series.c_str(), method.setting.c_str(), speed, dt,
              duration, errors.steps, name(stability), gap, errors.relative_energy_gain(), errors.relative_energy_drift(),
              errors.energy_scale, knock);
    }
    std::printf("\n");
  }
  std::printf("# cell: outcome, largest joint gap / link, knock (m)\n");
}

// ---------------------------------------------------------------------------------------------
// springs: the eq. 3.15 check.

void spring_check(bool quick, Output& out) {
  const std::vector<double> stiffnesses =
      quick ? std::vector<double>{1e4, 1e5} : std::vector<double>{1e3, 3e3, 1e4, 2e4, 3e4, 1e5, 3e5, 1e6};
  // Δt from 1/1000 s up by √2 to 1/15.6 s: 13 cells.
  std::vector<double> steps;
  for (int j = 0; j <= 12; ++j) steps.push_back(1e-3 * std::pow(2.0, 0.5 * j));
  const double duration = quick ? 2 : 10, damping = kSceneDamping;
  const Model chain = stress_chain(1);
  std::printf("# eq. 3.15 check: the equal-mass 10-link chain under explicit springs, c = %g N s/m, %g s per run;\n"
              "# diverged = non-finite or energy gain > %g x m*g*sum(L) (gaps not counted: a weak spring tears the chain"
              " without blowing up); dt from 1/1000 s up by sqrt(2)\n",
              damping, duration, kBounds.energy_gain);
  std::printf("# PASS: every run more than one dt cell (x sqrt(2)) from the predicted boundary is stable below it and"
              " diverged above it\n");
  std::printf("%-28s %9s %11s %11s %11s  %-13s  %s\n", "integrator", "k (N/m)", "omega_max", "predicted", "measured", "check",
              "map (dt up; . stable, x diverged, | predicted boundary)");
  out.header("section,integrator,stiffness,damping,dt,duration,steps,stability,max_gap,energy_gain,omega_max,predicted_stable_dt,predicted_stable,diverged");
  struct Named { const char* name; Integrator integrator; };
  for (const Named integrator : {Named{"semi-implicit euler", Integrator::semi_implicit_euler},
                                 Named{"forward euler", Integrator::euler}}) {
    for (const double k : stiffnesses) {
      const std::vector<double> frequencies = spring_mode_frequencies(chain, k);
      const double omega_max = *std::max_element(frequencies.begin(), frequencies.end());
      const double predicted = predicted_largest_stable_step(integrator.integrator, frequencies, k, damping);
      std::string map;
      double measured = 0;  // the largest Δt below which every run was stable
      bool all_stable_so_far = true, pass = true;
      double held_gap = std::numeric_limits<double>::quiet_NaN();  // the largest gap of the smallest-Δt run
      for (const double dt : steps) {
        Simulation simulation(chain, spring_method(integrator.name, integrator.integrator, k, damping, dt));
        const RunErrors errors = observe_run(simulation, duration, 0, blew_up).errors;
        const bool stable = !blew_up(errors);
        const bool predicted_stable = dt <= predicted;
        if (!predicted_stable && map.find('|') == std::string::npos) map += '|';  // the predicted boundary
        map += stable ? '.' : 'x';
        // Agreement is required away from the boundary: below predicted/√2 stable, above predicted·√2 diverged.
        if (dt < predicted / std::sqrt(2.0) && !stable) pass = false;
        if (dt > predicted * std::sqrt(2.0) && stable) pass = false;
        if (all_stable_so_far && stable) measured = dt;
        if (dt == steps.front() && stable) held_gap = std::max(errors.max_joint_gap, errors.max_link_stretch);
        all_stable_so_far = all_stable_so_far && stable;
        out.row("springs,%s,%g,%g,%.9g,%g,%ld,%s,%.6g,%.6g,%.6g,%.6g,%d,%d", integrator.name, k, damping, dt, duration, errors.steps,
                name(classify(errors, kBounds)), std::max(errors.max_joint_gap, errors.max_link_stretch), errors.relative_energy_gain(),
                omega_max, predicted, predicted_stable ? 1 : 0, stable ? 0 : 1);
      }
      // A spring too weak to hold the chain (gap beyond the bound in the stable smallest-Δt run) tears it:
      // the linearization about the closed joints no longer describes it.
      const bool torn = held_gap > kBounds.joint_gap;  // NaN (the smallest Δt diverged): not judged
      std::printf("%-28s %9g %11.4g %11.4g %11.4g  %-13s  %s\n", integrator.name, k, omega_max, predicted, measured,
                  (std::string(pass ? "PASS" : "FAIL") + (torn ? " (torn)" : "")).c_str(), map.c_str());
      std::fflush(stdout);
    }
  }
}

// ---------------------------------------------------------------------------------------------

int usage_error(const std::string& message) {
  std::fprintf(stderr, "stability_stress: %s (usage: stability_stress grid|long|impacts|springs [--quick] [--csv FILE])\n",
               message.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage_error("missing mode");
  const std::string mode = argv[1];
  if (mode != "grid" && mode != "long" && mode != "impacts" && mode != "springs") return usage_error("unknown mode '" + mode + "'");
  bool quick = false;
  Output out;
  for (int a = 2; a < argc; ++a) {
    const std::string flag = argv[a];
    if (flag == "--quick") {
      quick = true;
    } else if (flag == "--csv") {
      if (a + 1 >= argc) return usage_error("--csv needs a file name");
      out.csv.emplace(argv[++a]);
      if (!*out.csv) return usage_error(std::string("cannot write '") + argv[a] + "'");
    } else {
      return usage_error("unknown option '" + flag + "'");
    }
  }
  try {
    if (mode == "grid") grid(quick, out);
    else if (mode == "long") long_runs(quick, out);
    else if (mode == "impacts") impacts(quick, out);
    else spring_check(quick, out);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "stability_stress: %s\n", error.what());
    return 1;
  }
  return 0;
}
