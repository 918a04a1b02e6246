#include "tools/cli/trajectory.hpp"

#include <cstdio>
#include <ostream>
#include <string>
#include <type_traits>

#include "limber/kernel/rigid/rigid_scene.hpp"
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

template <typename Scalar>
void write_header(std::ostream& csv, const Model& model, const VerletState<Scalar>& state) {
  for (const ParticleOrigin& origin : state.particle_origins) {
    const std::string name = particle_name(model, origin);
    csv << ',' << name << "_x," << name << "_y," << name << "_z";
  }
}
template <typename Scalar>
void write_row(std::ostream& csv, const VerletState<Scalar>& state) {
  const auto& p = state.particles;
  for (std::size_t i = 0; i < p.size(); ++i) write_point<Scalar>(csv, p.position_x[i], p.position_y[i], p.position_z[i]);
}

void write_header(std::ostream& csv, const Model& model, const RigidScene&) {
  for (const Body& body : model.bodies) {
    for (const char* end : {".head", ".tail"}) csv << ',' << body.name << end << "_x," << body.name << end << "_y," << body.name << end << "_z";
  }
  for (std::size_t k = 0; k < model.balls.size(); ++k) {
    const std::string name = ball_name(model, k);
    csv << ',' << name << "_x," << name << "_y," << name << "_z";
  }
}
void write_row(std::ostream& csv, const RigidScene& state) {
  auto write = [&](const Eigen::Vector3d& x) { write_point<double>(csv, x.x(), x.y(), x.z()); };
  for (std::size_t b = 0; b < state.ball_begin; ++b) {
    const double half = 0.5 * state.shapes.length[b];
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
