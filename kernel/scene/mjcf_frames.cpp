// MJCF frames: an element's orientation from quat, axisangle, euler, xyaxes or zaxis, computed
// step for step as MuJoCo 2.2.2 does (src/user/user_objects.cc mjCAlternative::Set,
// src/user/user_util.cc mjuu_z2quat and mjuu_frame2quat), so the quaternions agree with
// body_quat and geom_quat to rounding.
#include <cmath>
#include <numbers>

#include "limber/kernel/scene/mjcf_reader.hpp"

namespace limber::mjcf::detail {

namespace {

Eigen::Quaterniond wxyz(double w, double x, double y, double z) { return Eigen::Quaterniond(w, x, y, z); }

// MuJoCo's mjuu_frame2quat: the rotation whose columns are x, y, z (unit, orthogonal).
Eigen::Quaterniond frame_to_quaternion(const Eigen::Vector3d& x, const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
  const Eigen::Vector3d* mat[3] = {&x, &y, &z};  // mat[c](r)
  auto m = [&](int c, int r) { return (*mat[c])(r); };
  double q[4];
  if (m(0, 0) + m(1, 1) + m(2, 2) > 0) {
    q[0] = 0.5 * std::sqrt(1 + m(0, 0) + m(1, 1) + m(2, 2));
    q[1] = 0.25 * (m(1, 2) - m(2, 1)) / q[0];
    q[2] = 0.25 * (m(2, 0) - m(0, 2)) / q[0];
    q[3] = 0.25 * (m(0, 1) - m(1, 0)) / q[0];
  } else if (m(0, 0) > m(1, 1) && m(0, 0) > m(2, 2)) {
    q[1] = 0.5 * std::sqrt(1 + m(0, 0) - m(1, 1) - m(2, 2));
    q[0] = 0.25 * (m(1, 2) - m(2, 1)) / q[1];
    q[2] = 0.25 * (m(1, 0) + m(0, 1)) / q[1];
    q[3] = 0.25 * (m(2, 0) + m(0, 2)) / q[1];
  } else if (m(1, 1) > m(2, 2)) {
    q[2] = 0.5 * std::sqrt(1 - m(0, 0) + m(1, 1) - m(2, 2));
    q[0] = 0.25 * (m(2, 0) - m(0, 2)) / q[2];
    q[1] = 0.25 * (m(1, 0) + m(0, 1)) / q[2];
    q[3] = 0.25 * (m(2, 1) + m(1, 2)) / q[2];
  } else {
    q[3] = 0.5 * std::sqrt(1 - m(0, 0) - m(1, 1) + m(2, 2));
    q[0] = 0.25 * (m(0, 1) - m(1, 0)) / q[3];
    q[1] = 0.25 * (m(2, 0) + m(0, 2)) / q[3];
    q[2] = 0.25 * (m(2, 1) + m(1, 2)) / q[3];
  }
  return normalized_quaternion(Eigen::Vector4d(q[0], q[1], q[2], q[3]));
}

Eigen::Quaterniond from_xyaxes(const Eigen::Matrix<double, 6, 1>& axes) {
  Eigen::Vector3d x = axes.head<3>();
  Eigen::Vector3d y = axes.tail<3>();
  if (x.norm() < mj_eps) throw FrameError{"xyaxes", "the x axis is too small"};
  x /= x.norm();
  y -= x * x.dot(y);  // y made orthogonal to x
  if (y.norm() < mj_eps) throw FrameError{"xyaxes", "the y axis is too small (or parallel to x)"};
  y /= y.norm();
  Eigen::Vector3d z = x.cross(y);
  if (z.norm() < mj_eps) throw FrameError{"xyaxes", "cross(x, y) is too small"};
  z /= z.norm();
  return frame_to_quaternion(x, y, z);
}

// Each angle about the named axis: lower case about the moving axes (post-multiplied), upper
// case about the fixed ones (pre-multiplied).
Eigen::Quaterniond from_euler(const Eigen::Vector3d& angles, const Compiler& compiler) {
  Eigen::Quaterniond q = wxyz(1, 0, 0, 0);
  for (int i = 0; i < 3; ++i) {
    const double angle = compiler.degree ? angles(i) / 180.0 * std::numbers::pi : angles(i);
    const double s = std::sin(angle / 2);
    Eigen::Quaterniond turn = wxyz(std::cos(angle / 2), 0, 0, 0);
    const char axis = compiler.eulerseq[i];
    if (axis == 'x' || axis == 'X') turn.x() = s;
    if (axis == 'y' || axis == 'Y') turn.y() = s;
    if (axis == 'z' || axis == 'Z') turn.z() = s;
    const bool moving = axis == 'x' || axis == 'y' || axis == 'z';
    q = moving ? q * turn : turn * q;
  }
  return normalized_quaternion(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()));
}

}  // namespace

Eigen::Quaterniond normalized_quaternion(const Eigen::Vector4d& q) {
  const double norm = q.norm();
  if (norm < mj_eps) return wxyz(q(0), q(1), q(2), q(3));  // MuJoCo's mjuu_normvec leaves it
  return wxyz(q(0) / norm, q(1) / norm, q(2) / norm, q(3) / norm);
}

Eigen::Quaterniond z_axis_to_quaternion(const Eigen::Vector3d& direction) {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ().cross(direction);
  const double s = axis.norm();
  if (s < 1e-10) {
    axis = Eigen::Vector3d::UnitX();
  } else {
    axis /= s;
  }
  const double angle = std::atan2(s, direction(2));
  const double h = std::sin(angle / 2);
  return wxyz(std::cos(angle / 2), axis(0) * h, axis(1) * h, axis(2) * h);
}

OrientationSpec read_orientation(const Reader& reader, const Node& element) {
  OrientationSpec spec;
  std::string given;
  auto read = [&](const char* attribute, auto& slot, auto value) {
    if (!reader.numbers(element, attribute, std::span<double>(value.data(), value.size()), true)) return;
    if (!given.empty()) {
      reader.fail(element, tag(element, attribute),
                  std::string("two orientations given (") + given + " and " + attribute + "): give one");
    }
    given = attribute;
    slot = value;
  };
  read("quat", spec.quat, Eigen::Vector4d());
  read("axisangle", spec.axisangle, Eigen::Vector4d());
  read("euler", spec.euler, Eigen::Vector3d());
  read("xyaxes", spec.xyaxes, Eigen::Matrix<double, 6, 1>());
  read("zaxis", spec.zaxis, Eigen::Vector3d());
  return spec;
}

Eigen::Quaterniond resolve_orientation(const OrientationSpec& spec, const Eigen::Vector4d& fallback,
                                       const Compiler& compiler) {
  if (spec.quat) {
    if (spec.quat->norm() < mj_eps) throw FrameError{"quat", "the quaternion is zero"};
    return normalized_quaternion(*spec.quat);
  }
  if (spec.axisangle) {
    Eigen::Vector3d axis = spec.axisangle->head<3>();
    const double angle = compiler.degree ? (*spec.axisangle)(3) / 180.0 * std::numbers::pi : (*spec.axisangle)(3);
    if (axis.norm() < mj_eps) throw FrameError{"axisangle", "the axis is too small"};
    axis /= axis.norm();
    const double s = std::sin(angle / 2);
    return wxyz(std::cos(angle / 2), s * axis(0), s * axis(1), s * axis(2));
  }
  if (spec.xyaxes) return from_xyaxes(*spec.xyaxes);
  if (spec.zaxis) {
    Eigen::Vector3d z = *spec.zaxis;
    if (z.norm() < mj_eps) throw FrameError{"zaxis", "the axis is too small"};
    return z_axis_to_quaternion(z / z.norm());
  }
  if (spec.euler) return from_euler(*spec.euler, compiler);
  return normalized_quaternion(fallback);
}

}  // namespace limber::mjcf::detail
