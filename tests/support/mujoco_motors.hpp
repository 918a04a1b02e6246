// MuJoCo's humanoid driven by its motors, in MuJoCo 2.2.2 and in limber, body by body.
//
// The set-up: the model file lifted by kLift so that nothing touches the floor for the run, its
// joint limits off in both engines (the file's pose is outside the knees' ranges, −160° … −2°, so
// MuJoCo's limits would act from the first step), every motor at a constant control; MuJoCo
// integrates it with RK4 at 10⁻⁴ s (its reference), limber
// under one of `limber run`'s configurations ("weighted", "lagrange", ...) at its own step. Each
// limber body is compared with the MuJoCo geom it was made from, centre to centre: body "b" is
// MuJoCo body b's first geom, body "b/g" its geom g (kernel/scene/mjcf_model.cpp's names).
// Samples every kSampleInterval s, a whole number of steps of every step compared.
//
// A motor's response: the displacement it causes (the run with it on, minus the run with every
// control at zero) of the body MuJoCo moves most, projected on MuJoCo's displacement of that
// body, over MuJoCo's: 1 is MuJoCo's motion, 0 none, a negative number the wrong way.
//
// Used by tests/scene/mujoco_motors_test.cpp and bench/mujoco_motors.cpp (bench/models.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <mujoco/mujoco.h>

#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"
#include "tools/cli/cli.hpp"

namespace limber::mujoco_motors {

inline const std::filesystem::path kHumanoid = "/usr/share/mujoco/model/humanoid/humanoid.xml";
inline constexpr double kLift = 1.0;             ///< m: the lowest geom starts about 1 m up, falls 0.2 m in 0.2 s
inline constexpr double kSampleInterval = 0.01;  ///< s
inline constexpr double kReferenceStep = 1e-4;   ///< s, MuJoCo's RK4

/// Geom centres (m, world) per compared body, one vector per sample (t = 0, kSampleInterval, ...).
using Samples = std::vector<std::vector<Eigen::Vector3d>>;

/// A run: its samples, or why it has none past some time (a refusal at load, a divergence).
struct MotorRun {
  Samples samples;
  std::string failure;  ///< empty: it went all the way
  bool touched = false;    ///< MuJoCo's runs: a contact or limit row was active at some step
};

/// The controls of the all-motors run: 0.1·sin(a + 1) on motor a, every sign and size up to 0.1,
/// small enough that no limb touches another in MuJoCo's run of 0.2 s (MotorRun::touched says so).
inline std::vector<double> all_motor_controls(std::size_t actuators) {
  std::vector<double> controls(actuators);
  for (std::size_t a = 0; a < actuators; ++a) controls[a] = 0.1 * std::sin(static_cast<double>(a) + 1);
  return controls;
}

/// The file in MuJoCo, lifted, and the geoms limber's bodies came from.
class Mujoco {
 public:
  /// `body_names`: limber's bodies of the same file, in Model order (the compared bodies).
  Mujoco(const std::filesystem::path& file, const std::vector<std::string>& body_names) {
    char error[1000] = "";
    model_ = mj_loadXML(file.c_str(), nullptr, error, sizeof error);
    if (!model_) throw std::runtime_error(std::string("mj_loadXML: ") + error);
    model_->opt.integrator = mjINT_RK4;
    model_->opt.timestep = kReferenceStep;
    model_->opt.disableflags |= mjDSBL_LIMIT;
    data_ = mj_makeData(model_);
    for (const std::string& name : body_names) geoms_.push_back(geom_of(name));
  }
  ~Mujoco() {
    mj_deleteData(data_);
    mj_deleteModel(model_);
  }
  Mujoco(const Mujoco&) = delete;
  Mujoco& operator=(const Mujoco&) = delete;

  int actuators() const { return model_->nu; }

  /// `duration` s from the file's pose lifted by kLift, at rest, under constant `controls`.
  MotorRun run(const std::vector<double>& controls, double duration) {
    mj_resetData(model_, data_);
    data_->qpos[2] += kLift;  // the free joint's z
    for (int a = 0; a < model_->nu; ++a) data_->ctrl[a] = controls[static_cast<std::size_t>(a)];
    mj_forward(model_, data_);
    MotorRun out;
    const long steps = std::lround(duration / kReferenceStep), every = std::lround(kSampleInterval / kReferenceStep);
    out.samples.push_back(centres());
    for (long step = 1; step <= steps; ++step) {
      mj_step(model_, data_);
      out.touched |= data_->nefc > 0;
      if (step % every == 0) out.samples.push_back(centres());
    }
    return out;
  }

 private:
  int geom_of(const std::string& name) const {
    const std::size_t slash = name.find('/');
    if (slash != std::string::npos) return checked(mj_name2id(model_, mjOBJ_GEOM, name.substr(slash + 1).c_str()), name);
    const int body = checked(mj_name2id(model_, mjOBJ_BODY, name.c_str()), name);
    return checked(model_->body_geomnum[body] > 0 ? model_->body_geomadr[body] : -1, name);
  }
  static int checked(int id, const std::string& name) {
    if (id < 0) throw std::runtime_error("no MuJoCo geom for limber's body '" + name + "'");
    return id;
  }
  std::vector<Eigen::Vector3d> centres() const {
    std::vector<Eigen::Vector3d> out;
    for (const int g : geoms_) out.emplace_back(data_->geom_xpos[3 * g], data_->geom_xpos[3 * g + 1], data_->geom_xpos[3 * g + 2]);
    return out;
  }

  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<int> geoms_;
};

/// The file's bodies as limber loads it, lifted by kLift, its joints without limits.
inline Scene lifted_scene(const std::filesystem::path& file) {
  Scene scene = load_scene_file(file);
  const Model model = scene.model;
  scene.model.bodies.clear(), scene.model.joints.clear(), scene.model.gears.clear(), scene.model.actuators.clear();
  append_model(scene.model, model, "", Vector3(0, 0, kLift));
  for (Joint& joint : scene.model.joints) {
    joint.limits = JointLimits{};
    for (SerialAxis& axis : joint.serial_axes) axis.range.reset();
  }
  return scene;
}

/// Model body names, in order.
inline std::vector<std::string> body_names(const Scene& scene) {
  std::vector<std::string> names;
  for (const Body& body : scene.model.bodies) names.push_back(body.name);
  return names;
}

/// `duration` s of `scene` under `limber run --method <configuration> --dt <dt>`, constant `controls`.
inline MotorRun run_limber(Scene scene, const std::string& configuration, double dt, const std::vector<double>& controls, double duration) {
  MotorRun out;
  std::optional<World> world;
  try {
    const WorldOptions options = cli::options_for_scene(scene, {"--method", configuration, "--dt", std::to_string(dt)});
    world.emplace(std::move(scene.model), options);
  } catch (const std::exception& error) {
    out.failure = std::string("refused: ") + error.what();
    return out;
  }
  try {
    world->set_controls(controls);
  } catch (const WorldError& error) {  // a method that does not drive some axis
    out.failure = std::string("refused: ") + error.what();
    return out;
  }
  const std::vector<BodyId> bodies = world->bodies();
  const auto centres = [&] {
    std::vector<Eigen::Vector3d> at;
    for (const BodyId body : bodies) at.push_back(world->pose(body).position);
    return at;
  };
  const long steps = std::lround(duration / dt), every = std::lround(kSampleInterval / dt);
  out.samples.push_back(centres());
  for (long step = 1; step <= steps; ++step) {
    const StepStatus status = world->step(dt);
    if (status != StepStatus::ok) {
      out.failure = std::string(name(status)) + " at t = " + std::to_string(world->time()) + " s";
      return out;
    }
    if (step % every == 0) out.samples.push_back(centres());
  }
  return out;
}

/// The largest distance between a body of `run` and its geom in `reference`, over the samples
/// both have, m (infinity when `run` failed).
inline double largest_distance(const MotorRun& run, const MotorRun& reference) {
  if (!run.failure.empty()) return INFINITY;
  double largest = 0;
  for (std::size_t s = 0; s < std::min(run.samples.size(), reference.samples.size()); ++s) {
    for (std::size_t b = 0; b < run.samples[s].size(); ++b) largest = std::max(largest, (run.samples[s][b] - reference.samples[s][b]).norm());
  }
  return largest;
}

/// A motor's response (the file's comment): run/rest under a method, against reference/reference_rest.
struct Response {
  double ratio = NAN;    ///< 1: MuJoCo's motion (NaN: a run failed)
  std::size_t body = 0;  ///< the body MuJoCo moves most
};
inline Response response(const MotorRun& run, const MotorRun& rest, const MotorRun& reference, const MotorRun& reference_rest) {
  Response out;
  const std::vector<Eigen::Vector3d>&mj = reference.samples.back(), &mj_rest = reference_rest.samples.back();
  double most = -1;
  for (std::size_t b = 0; b < mj.size(); ++b) {
    if ((mj[b] - mj_rest[b]).norm() > most) most = (mj[b] - mj_rest[b]).norm(), out.body = b;
  }
  if (!run.failure.empty() || !rest.failure.empty()) return out;
  const Eigen::Vector3d expected = mj[out.body] - mj_rest[out.body];
  const Eigen::Vector3d got = run.samples.back()[out.body] - rest.samples.back()[out.body];
  out.ratio = got.dot(expected) / expected.squaredNorm();
  return out;
}

}  // namespace limber::mujoco_motors
