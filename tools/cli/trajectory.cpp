#include "tools/cli/trajectory.hpp"

#include <cstdio>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "limber/kernel/collision/rigid_contacts.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/scene/capsule_proxy.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/kernel/verlet/compile.hpp"  // particle_name

namespace limber::cli {
namespace {

// Round-trip digits: 17 for a double, 9 for a float.
template <typename Scalar>
constexpr int kDigits = std::is_same_v<Scalar, float> ? 9 : 17;

template <typename Scalar>
void write_point(std::ostream& csv, Scalar x, Scalar y, Scalar z) {
  char cell[96];
  std::snprintf(cell, sizeof cell, ",%.*g,%.*g,%.*g", kDigits<Scalar>, double(x), kDigits<Scalar>, double(y), kDigits<Scalar>,
                double(z));
  csv << cell;
}

// The Model whose bodies the state's body indices count: `model` itself, or, when the state has
// more bodies than it (a particle or Lagrange state running serial joints through virtual links,
// appended after the Model's bodies), its expansion, which names each link "<joint>/link<i>"
// (serial_links.hpp). `state_bodies` is the state's body count, balls left out.
const Model& model_as_compiled(const Model& model, std::size_t state_bodies, std::optional<SerialExpansion>& expansion) {
  if (state_bodies <= model.bodies.size()) return model;
  expansion = expand_serial_joints(model);
  if (expansion->model.bodies.size() != state_bodies) {  // a state compiled from another Model: no names to give
    throw std::logic_error("trajectory: the state has " + std::to_string(state_bodies) + " bodies, the Model's expansion " +
                           std::to_string(expansion->model.bodies.size()));
  }
  return expansion->model;
}

void write_point_names(std::ostream& csv, const std::string& name) { csv << ',' << name << "_x," << name << "_y," << name << "_z"; }

template <typename Scalar>
void write_header(std::ostream& csv, const Model& model, const VerletState<Scalar>& state) {
  std::optional<SerialExpansion> expansion;
  const Model& compiled = model_as_compiled(model, state.body_limb.size(), expansion);
  for (const ParticleOrigin& origin : state.particle_origins) write_point_names(csv, particle_name(compiled, origin));
}
template <typename Scalar>
void write_row(std::ostream& csv, const VerletState<Scalar>& state) {
  const auto& p = state.particles;
  for (std::size_t i = 0; i < p.size(); ++i) write_point<Scalar>(csv, p.position_x[i], p.position_y[i], p.position_z[i]);
}

void write_header(std::ostream& csv, const Model& model, const RigidScene& state) {
  std::optional<SerialExpansion> expansion;
  const Model& compiled = model_as_compiled(model, state.ball_begin, expansion);
  for (std::size_t b = 0; b < state.ball_begin; ++b) {
    for (const char* end : {".head", ".tail"}) write_point_names(csv, compiled.bodies[b].name + end);
  }
  for (std::size_t k = 0; k < model.balls.size(); ++k) write_point_names(csv, ball_name(model, k));
}
void write_row(std::ostream& csv, const RigidScene& state) {
  auto write = [&](const Eigen::Vector3d& x) { write_point<double>(csv, x.x(), x.y(), x.z()); };
  for (std::size_t b = 0; b < state.ball_begin; ++b) {
    // A box's or an ellipsoid's head and tail: its capsule proxy's, along its body axis (the
    // particles' limb ends, so every method writes the same points).
    const double half = 0.5 * capsule_proxy(model_shape(state, b)).length;
    write(world_point(state, b, Eigen::Vector3d(0, 0, half)));
    write(world_point(state, b, Eigen::Vector3d(0, 0, -half)));
  }
  for (std::size_t b = state.ball_begin; b < state.bodies.size(); ++b) write(state.bodies.state.position[b]);
}

}  // namespace

void write_trajectory_header(std::ostream& csv, const Model& model, const MethodState& state) {
  csv << "time";
  std::visit([&](const auto& s) { write_header(csv, model, s); }, state);
  csv << '\n';
}

void write_trajectory_row(std::ostream& csv, const MethodState& state) {
  std::visit(
      [&](const auto& s) {
        char cell[32];
        std::snprintf(cell, sizeof cell, "%.17g", double(s.time));
        csv << cell;
        write_row(csv, s);
      },
      state);
  csv << '\n';
}

}  // namespace limber::cli
