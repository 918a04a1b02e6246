#include "tools/viewer/view_state.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/world/world_internals.hpp"
#include "tools/cli/trajectory.hpp"

namespace limber::viewer {
namespace {

// A step's simulated time is spent when what is left is within this fraction of a step, so a
// frame of exactly k steps takes k steps despite rounding.
constexpr double kStepSlack = 1e-9;

// The body's largest joint gap relative to its link length (the run summary's measure).
double joint_gap(const Observation& observation) { return observation.max_joint_gap; }

template <typename T>
void push_bounded(std::deque<T>& values, const T& value, std::size_t capacity) {
  values.push_back(value);
  while (values.size() > capacity) values.pop_front();
}

// Where a ray first meets a capsule (its segment a–b and radius), as t along the ray, if it does:
// the ray's closest approach to the segment, refined to the surface (good enough to pick).
std::optional<double> ray_capsule(const Ray& ray, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  constexpr int kSamples = 64;  // picking needs no exact root: march the ray's closest distance
  const Eigen::Vector3d axis = b - a;
  const double length_squared = std::max(axis.squaredNorm(), 1e-18);
  auto distance_at = [&](double t) {
    const Eigen::Vector3d p = ray.origin + t * ray.direction;
    const double s = std::clamp((p - a).dot(axis) / length_squared, 0.0, 1.0);
    return (p - (a + s * axis)).norm();
  };
  // The closest approach of the ray to the segment's middle bounds where to look.
  const double centre_t = std::max(0.0, ((0.5 * (a + b)) - ray.origin).dot(ray.direction));
  const double span = 0.5 * std::sqrt(length_squared) + radius;
  const double t0 = std::max(0.0, centre_t - span), t1 = centre_t + span;
  for (int i = 0; i <= kSamples; ++i) {
    const double t = t0 + (t1 - t0) * i / kSamples;
    if (distance_at(t) <= radius) return t;
  }
  return std::nullopt;
}

}  // namespace

std::string method_name(const WorldOptions& options) {
  switch (options.method) {
    case Method::particles: return options.particles.rule == RelaxationRule::unweighted ? "unweighted" : "weighted";
    case Method::springs: return options.springs.integrator == Integrator::backward_euler ? "springs-implicit" : "springs-explicit";
    case Method::lagrange: return "lagrange";
    case Method::featherstone: return "featherstone";
  }
  return "weighted";
}

ViewState::ViewState(std::vector<std::string> run_arguments)
    : run_arguments_(std::move(run_arguments)), loaded_(cli::load_run(run_arguments_)) {
  method_name_ = viewer::method_name(loaded_.options);
  build_world();
  frame_scene();
}

ViewState::~ViewState() {
  if (!trajectory_) return;
  try {
    trajectory_->commit();
  } catch (const std::exception&) {
    // A destructor cannot report it; the .part is removed and nothing is left under the name.
  }
}

void ViewState::build_world(std::optional<World> compiled) {
  if (compiled) {
    world_ = std::move(compiled);
  } else {
    world_.emplace(loaded_.scene.model, loaded_.options);
  }
  steps_taken_ = 0, unspent_seconds_ = 0;
  drag_.reset(), last_loads_.clear();
  history_ = History{};
  if (picked_ && *picked_ >= world_->model().bodies.size()) picked_.reset();
  trajectory_.reset();  // a reset starts the trajectory again
  if (!loaded_.out_path.empty()) {
    trajectory_.emplace(loaded_.out_path, "--out", std::vector<std::filesystem::path>{loaded_.scene_path});
    cli::write_trajectory_header(trajectory_->stream(), world_->model(), world_->internals().state);
    cli::write_trajectory_row(trajectory_->stream(), world_->internals().state);
  }
}

// Aims the camera at the body from the side, far enough to see all of it.
void ViewState::frame_scene() {
  const Model& model = world_->model();
  if (model.bodies.empty()) return;
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), high = -low;
  for (const Body& body : model.bodies) {
    const BoundingSphere sphere = limb_sphere(body.shape, body.position, body.orientation());
    low = low.cwiseMin((sphere.centre.array() - sphere.radius).matrix());
    high = high.cwiseMax((sphere.centre.array() + sphere.radius).matrix());
  }
  camera.target = 0.5 * (low + high);
  const double size = (high - low).norm();
  camera.distance = std::clamp(0.6 * size / std::tan(0.5 * camera.fov_y), 1.5, 400.0);
}

int ViewState::advance(double seconds) {
  int steps = 0;
  if (playing_) {
    const double dt = world_->model().settings.time_step;
    unspent_seconds_ += speed * seconds;
    while (unspent_seconds_ >= dt * (1 - kStepSlack)) {
      step_once();
      unspent_seconds_ = std::max(0.0, unspent_seconds_ - dt);
      ++steps;
    }
  } else if (step_requested_) {
    step_once();
    ++steps;
  }
  step_requested_ = false;
  return steps;
}

void ViewState::step_once() {
  apply_loads();
  const auto before = std::chrono::steady_clock::now();
  world_->step();
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - before).count();
  ++steps_taken_;
  if (trajectory_) cli::write_trajectory_row(trajectory_->stream(), world_->internals().state);
  record(ms);
}

// The arrow keys' push and the drag spring, on the picked limb over the coming step.
void ViewState::apply_loads() {
  last_loads_.clear();
  World& world = *world_;
  if (picked_ && std::any_of(std::begin(held_), std::end(held_), [](bool b) { return b; })) {
    const BodyId body = world.bodies()[*picked_];
    // Camera-relative directions on the ground: up pushes away from the eye, right to its right.
    Eigen::Vector3d forward = camera.target - camera.eye();
    forward.z() = 0;
    forward = forward.norm() > 0 ? Eigen::Vector3d(forward.normalized()) : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d direction = (held_[1] - held_[0]) * right + (held_[2] - held_[3]) * forward;
    if (direction.norm() > 0) {
      const Eigen::Vector3d force = push_acceleration * world.body_description(body).mass * direction.normalized();
      const Eigen::Vector3d at = world.pose(body).position;
      world.apply_force(body, force, at);
      last_loads_.emplace_back(at, force);
    }
  }
  if (drag_) {
    const BodyId body = world.bodies()[drag_->body];
    const Pose pose = world.pose(body);
    const Eigen::Vector3d at = pose.position + pose.orientation * drag_->local_point;
    const Motion motion = world.motion(body);
    const Eigen::Vector3d velocity = motion.linear + motion.angular.cross(at - pose.position);
    const double mass = world.body_description(body).mass;
    // Critically damped per unit mass: c = 2√k.
    const Eigen::Vector3d force = mass * (drag_stiffness * (drag_->target - at) - 2 * std::sqrt(drag_stiffness) * velocity);
    world.apply_force(body, force, at);
    last_loads_.emplace_back(at, force);
  }
}

void ViewState::record(double step_ms) {
  const Observation observation = world_->observe();
  push_bounded(history_.energy, float(observation.energy()), History::kSteps);
  push_bounded(history_.joint_gap, float(joint_gap(observation)), History::kSteps);
  push_bounded(history_.step_ms, float(step_ms), History::kSteps);
  push_bounded(history_.path, observation.body_centre_of_mass, History::kSteps);
}

void ViewState::handle(const InputEvent& event, int width, int height) {
  std::visit(
      [&](const auto& e) {
        using E = std::decay_t<decltype(e)>;
        if constexpr (std::is_same_v<E, KeyEvent>) on_key(e);
        if constexpr (std::is_same_v<E, ButtonEvent>) on_button(e, width, height);
        if constexpr (std::is_same_v<E, CursorEvent>) on_cursor(e, width, height);
        if constexpr (std::is_same_v<E, ScrollEvent>) camera.zoom(e.steps);
      },
      event);
}

void ViewState::on_key(const KeyEvent& event) {
  switch (event.key) {
    case Key::left: held_[0] = event.down; return;
    case Key::right: held_[1] = event.down; return;
    case Key::up: held_[2] = event.down; return;
    case Key::down: held_[3] = event.down; return;
    default: break;
  }
  if (!event.down) return;
  if (event.key <= Key::f8) {
    const std::size_t body = std::size_t(event.key) - std::size_t(Key::f1);
    if (body < world_->model().bodies.size()) pick(body);
    return;
  }
  switch (event.key) {
    case Key::f9: overlays.bounding_volumes = !overlays.bounding_volumes; break;
    case Key::space: playing_ = !playing_; break;
    case Key::step: playing_ = false, step_requested_ = true; break;
    case Key::reset: reset(); break;
    case Key::launch: launch(); break;
    case Key::slow_motion: speed = speed < 1 ? 1 : 0.25; break;
    default: break;
  }
}

// Left on a limb: pick it and drag it with the spring; left elsewhere: orbit (and unpick);
// right: pan; middle: orbit.
void ViewState::on_button(const ButtonEvent& event, int width, int height) {
  cursor_ = event.cursor;
  if (!event.down) {
    if (orbiting_ == event.button) orbiting_.reset();
    if (event.button == Button::left) drag_.reset();
    return;
  }
  if (event.button == Button::left) {
    const Ray ray = camera.ray(event.cursor.x(), event.cursor.y(), width, height);
    const std::optional<std::size_t> body = hit(ray);
    pick(body);
    if (body) {
      const BodyId id = world_->bodies()[*body];
      const Pose pose = world_->pose(id);
      std::vector<LimbSegment> segments;
      world_->segments(segments);
      const LimbSegment& limb = segments[*body];
      const std::optional<double> t = ray_capsule(ray, limb.head, limb.tail, limb.radius);
      const Eigen::Vector3d grab = ray.origin + t.value_or(0) * ray.direction;
      const double depth = (grab - ray.origin).dot(camera.target - camera.eye()) / camera.distance;
      drag_ = Drag{*body, pose.orientation.conjugate() * (grab - pose.position), grab, depth};
      world_->wake(id);
      return;
    }
  }
  orbiting_ = event.button;
}

void ViewState::on_cursor(const CursorEvent& event, int width, int height) {
  const Eigen::Vector2d move = event.cursor - cursor_;
  cursor_ = event.cursor;
  if (drag_) {
    // The target stays at its grab depth: on the plane facing the camera through it.
    const Ray ray = camera.ray(event.cursor.x(), event.cursor.y(), width, height);
    const Eigen::Vector3d forward = (camera.target - camera.eye()) / camera.distance;
    const double along = ray.direction.dot(forward);
    if (along > 1e-6) drag_->target = ray.origin + (drag_->depth / along) * ray.direction;
    return;
  }
  if (orbiting_ == Button::right) camera.pan(move.x(), move.y(), height);
  else if (orbiting_) camera.orbit(move.x(), move.y());
}

void ViewState::pick(std::optional<std::size_t> body) {
  picked_ = body;
  if (body) world_->wake(world_->bodies()[*body]);
}

std::optional<std::size_t> ViewState::hit(const Ray& ray) const {
  std::optional<std::size_t> best;
  double nearest = std::numeric_limits<double>::infinity();
  std::vector<LimbSegment> segments;
  world_->segments(segments);
  for (std::size_t i = 0; i < world_->model().bodies.size(); ++i) {
    // A thin limb is hard to click: it takes clicks within 2 cm of its surface.
    const std::optional<double> t = ray_capsule(ray, segments[i].head, segments[i].tail, segments[i].radius + 0.02);
    if (t && *t < nearest) nearest = *t, best = i;
  }
  return best;
}

BallId ViewState::launch() {
  const Eigen::Vector3d direction = launcher.direction.norm() > 0 ? Eigen::Vector3d(launcher.direction.normalized())
                                                                  : Eigen::Vector3d(-1, 0, 0);
  const Eigen::Vector3d target =
      picked_ ? world_->pose(world_->bodies()[*picked_]).position : world_->observe().body_centre_of_mass;
  Ball ball;
  ball.radius = launcher.radius, ball.mass = launcher.mass, ball.restitution = launcher.restitution;
  ball.position = target - launcher.distance * direction;
  ball.velocity = launcher.speed * direction;
  return world_->add_ball(ball);
}

void ViewState::reset() { build_world(); }

bool ViewState::reload(std::vector<std::string> run_arguments) {
  try {
    cli::LoadedRun loaded = cli::load_run(run_arguments);
    loaded.options = loaded_.options;  // the method settings stay those chosen
    World compiled(loaded.scene.model, loaded.options);  // a model the method cannot take is refused here
    loaded_ = std::move(loaded);
    run_arguments_ = std::move(run_arguments);
    build_world(std::move(compiled));
  } catch (const std::exception& error) {
    error_ = error.what();
    return false;
  }
  error_.clear();
  frame_scene();
  return true;
}

bool ViewState::set_method(const std::string& method, int iterations, int substeps, ProjectionRule projection) {
  try {
    WorldOptions options = cli::options_for_method(method, loaded_.scene.methods);
    if (options.method == Method::particles) {
      if (iterations < 1 || substeps < 1 || substeps > kMaxSubsteps) throw std::invalid_argument("sweeps must be >= 1 and substeps in [1, 10000]");
      options.particles.relaxation.iterations = iterations;
      options.particles.relaxation.substeps = substeps;
      options.particles.relaxation.projection = projection;
    }
    World compiled(loaded_.scene.model, options);
    loaded_.options = options;
    method_name_ = method;
    build_world(std::move(compiled));
  } catch (const std::exception& error) {
    error_ = error.what();
    return false;
  }
  error_.clear();
  return true;
}

bool ViewState::set_friction(double friction) {
  if (!loaded_.scene.model.ground) {
    error_ = "friction: the scene '" + loaded_.scene.model.name + "' has no ground";
    return false;
  }
  if (!(friction >= 0) || !std::isfinite(friction)) {
    error_ = "friction: must be finite and >= 0";
    return false;
  }
  error_.clear();
  loaded_.scene.model.ground->friction = friction;
  build_world();
  return true;
}

bool ViewState::set_body(const std::string& variant) {
  std::vector<std::string> arguments;
  for (std::size_t i = 0; i < run_arguments_.size(); ++i) {
    if (run_arguments_[i] == "--body") {
      ++i;  // and its value
      continue;
    }
    if (run_arguments_[i].starts_with("--body=")) continue;
    arguments.push_back(run_arguments_[i]);
  }
  if (!variant.empty()) arguments.insert(arguments.end(), {"--body", variant});
  return reload(std::move(arguments));
}

}  // namespace limber::viewer
