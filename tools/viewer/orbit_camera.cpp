#include "tools/viewer/orbit_camera.hpp"

#include <algorithm>
#include <cmath>

namespace limber::viewer {
namespace {

constexpr double kRadiansPerPixel = 0.005;
constexpr double kNear = 0.02, kFar = 1000;

// The eye's frame: forward (eye → target), right and up, world.
struct Basis {
  Eigen::Vector3d forward, right, up;
};
Basis basis(const OrbitCamera& camera) {
  const Eigen::Vector3d to_eye(std::cos(camera.pitch) * std::cos(camera.yaw), std::cos(camera.pitch) * std::sin(camera.yaw),
                               std::sin(camera.pitch));
  Basis b;
  b.forward = -to_eye;
  b.right = b.forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  b.up = b.right.cross(b.forward);
  return b;
}

}  // namespace

void OrbitCamera::orbit(double dx, double dy) {
  yaw -= kRadiansPerPixel * dx;
  pitch = std::clamp(pitch + kRadiansPerPixel * dy, -1.5, 1.5);
}

void OrbitCamera::pan(double dx, double dy, int height) {
  // One pixel at the target's depth spans this many metres.
  const double metres_per_pixel = 2 * distance * std::tan(0.5 * fov_y) / std::max(height, 1);
  const Basis b = basis(*this);
  target += metres_per_pixel * (-dx * b.right + dy * b.up);
}

void OrbitCamera::zoom(double steps) { distance = std::clamp(distance * std::pow(0.88, steps), 0.1, 500.0); }

Eigen::Vector3d OrbitCamera::eye() const { return target - distance * basis(*this).forward; }

CameraMatrices OrbitCamera::matrices(int width, int height) const {
  const Basis b = basis(*this);
  const Eigen::Vector3d e = eye();
  CameraMatrices m;
  m.eye = e.cast<float>();
  // OpenGL's lookAt: rows right, up, −forward; the eye at the origin.
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = b.right.transpose();
  view.block<1, 3>(1, 0) = b.up.transpose();
  view.block<1, 3>(2, 0) = -b.forward.transpose();
  view(0, 3) = -b.right.dot(e), view(1, 3) = -b.up.dot(e), view(2, 3) = b.forward.dot(e);
  m.view = view.cast<float>();
  // OpenGL's perspective projection (gluPerspective).
  const double f = 1 / std::tan(0.5 * fov_y), aspect = double(std::max(width, 1)) / std::max(height, 1);
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  projection(0, 0) = f / aspect, projection(1, 1) = f;
  projection(2, 2) = (kFar + kNear) / (kNear - kFar), projection(2, 3) = 2 * kFar * kNear / (kNear - kFar);
  projection(3, 2) = -1;
  m.projection = projection.cast<float>();
  return m;
}

Ray OrbitCamera::ray(double x, double y, int width, int height) const {
  const Basis b = basis(*this);
  const double half_height = std::tan(0.5 * fov_y), aspect = double(std::max(width, 1)) / std::max(height, 1);
  const double u = (2 * (x + 0.5) / std::max(width, 1) - 1) * half_height * aspect;
  const double v = (1 - 2 * (y + 0.5) / std::max(height, 1)) * half_height;
  return Ray{eye(), (b.forward + u * b.right + v * b.up).normalized()};
}

}  // namespace limber::viewer
