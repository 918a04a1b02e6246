// The projection of joint rows (kernel/particles/joint_rows.hpp) over one block of a colour,
// written once for one lane (ScalarLanes: the overflow and the reference) and for xsimd
// registers (SimdLanes), with the same operations in the same order in every lane, so the two
// give the same bits (atan2 too: atan2_lanes, a polynomial written once for both).
//
// A block is one row kind. For each lane: gather both sides' particles (positions, inverse
// masses), build each side as a rigid cluster — centre of mass c, inertia tensor
// I = Σ m(|r|²E − r rᵀ) about it and its pseudo-inverse (a stick cannot turn about its own
// axis), its frame (v, w, u) — evaluate the kind's C and J_B, and apply the XPBD update
// (Macklin et al. 2016, eq. 18; Müller et al. 2020, eq. 14 for angular rows):
//   C = (C_raw − τ) − clamp(C_raw − τ, lower, upper),   α̃ = 1/(k_eff·h²),
//   Δλ = (−C − α̃λ)/(Jᵀ I_A⁺ J + Jᵀ I_B⁺ J + α̃),  λ ← clamp(λ + Δλ, ±friction·h²),
//   Δφ_B = I_B⁺ J Δλ,  Δφ_A = −I_A⁺ J Δλ,  Δx_k = Δφ × r_k on each side's particles.
// A drive's spring k and damper c are folded into one row (an implicit Euler PD): the torque
// k(τ_t − q) + c(ω_t − (q − q_s)/h) is k_eff(τ − q) with k_eff = k + c/h and
// τ = (k·τ_t + (c/h)(q_s + ω_t h))/k_eff, q_s the coordinate at the substep's start.
// Point rows are linear: C = Σ c_k x_k, Δx_k = −c_k w_k C / Σ c_j² w_j.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "limber/kernel/particles/joint_rows.hpp"
#include "limber/kernel/relaxation/batch_projection.hpp"

namespace limber::joint_projection {

template <typename V>
struct Vec3 {
  V x, y, z;
  friend Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3 operator*(const V& s, const Vec3& a) { return {s * a.x, s * a.y, s * a.z}; }
};
template <typename V>
V dot(const Vec3<V>& a, const Vec3<V>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename V>
Vec3<V> cross(const Vec3<V>& a, const Vec3<V>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// A symmetric 3×3 matrix (xx, yy, zz, xy, xz, yz).
template <typename V>
struct Sym3 {
  V xx, yy, zz, xy, xz, yz;
  Vec3<V> operator*(const Vec3<V>& a) const {
    return {xx * a.x + xy * a.y + xz * a.z, xy * a.x + yy * a.y + yz * a.z, xz * a.x + yz * a.y + zz * a.z};
  }
};

template <typename Lanes>
typename Lanes::value min_lanes(typename Lanes::value a, typename Lanes::value b) {
  return Lanes::select(a < b, a, b);
}

/// atan2(y, x), rad, in [−π, π] (π for y = −0, x < 0; 0 for y = x = 0), within 3 ulp of the
/// exact angle in double and float (2.1 the worst measured, just past tan(π/8), where π/4 + atan
/// cancels; tests/verlet/joint_rows_test.cpp), with the same operations in every lane, so that a
/// lane gives ScalarLanes' bits (the C library's, called lane by lane, cost a limit row 5–11 %
/// more: bench/speed.md). The octant's ratio t = min/max(|x|, |y|) is carried into
/// [−tan(π/8), tan(π/8)] by atan(t) = π/4 + atan((t − 1)/(t + 1)) (one division either way), where
/// atan(t) = t + t·z·P(z), z = t², P of degree 9: a least-squares fit for relative error on
/// Chebyshev nodes in 50-digit arithmetic, 1.4·10⁻¹⁶ at most in double.
template <typename Lanes>
typename Lanes::value atan2_lanes(typename Lanes::value y, typename Lanes::value x) {
  using V = typename Lanes::value;
  using Scalar = std::remove_cvref_t<decltype(Lanes::reduce_max(V{}))>;
  constexpr double kCoefficients[] = {-0.3333333333333000981514018,  0.1999999999906213235857994, -0.1428571419337301018937227,
                                      0.1111110658583805699874943,   -0.09090781004487848926179609, 0.07690050350453657850526366,
                                      -0.06640978676645640817487306, 0.05691851840917153560304961, -0.04357253738852810416265247,
                                      0.02123880364848641113598034};
  constexpr double kTanEighthPi = 0.41421356237309504880, kQuarterPi = 0.78539816339744830962;
  const V zero = Lanes::broadcast(Scalar(0));
  const V ax = Lanes::abs(x), ay = Lanes::abs(y);
  const auto swapped = ay > ax;
  const V low = Lanes::select(swapped, ax, ay), high = Lanes::select(swapped, ay, ax);
  const auto reduced = low > Lanes::broadcast(Scalar(kTanEighthPi)) * high;
  const V numerator = Lanes::select(reduced, low - high, low);
  const V denominator = Lanes::select(high == zero, Lanes::broadcast(Scalar(1)), Lanes::select(reduced, low + high, high));
  const V t = numerator / denominator, z = t * t;
  V p = Lanes::broadcast(Scalar(kCoefficients[9]));
  for (int k = 8; k >= 0; --k) p = p * z + Lanes::broadcast(Scalar(kCoefficients[k]));
  V angle = t + t * (z * p);
  angle = Lanes::select(reduced, Lanes::broadcast(Scalar(kQuarterPi)) + angle, angle);
  angle = Lanes::select(swapped, Lanes::broadcast(Scalar(2 * kQuarterPi)) - angle, angle);
  angle = Lanes::select(x < zero, Lanes::broadcast(Scalar(4 * kQuarterPi)) - angle, angle);
  return Lanes::select(y < zero, zero - angle, angle);
}

/// v/|v|, or `fallback` where |v| is 0.
template <typename Lanes>
Vec3<typename Lanes::value> normalized(const Vec3<typename Lanes::value>& v, const Vec3<typename Lanes::value>& fallback) {
  using V = typename Lanes::value;
  const V length = Lanes::sqrt(dot(v, v));
  const auto valid = length > Lanes::broadcast(0);
  const V inverse = Lanes::broadcast(1) / Lanes::select(valid, length, Lanes::broadcast(1));
  return {Lanes::select(valid, v.x * inverse, fallback.x), Lanes::select(valid, v.y * inverse, fallback.y),
          Lanes::select(valid, v.z * inverse, fallback.z)};
}

/// Particle coordinates as the joint kernels read and write them: positions (or velocities) and
/// the previous positions (the substep's start), SoA.
template <typename Scalar>
struct JointFields {
  Scalar *x, *y, *z;           ///< moved: positions, or velocities in the velocity stage
  const Scalar *px, *py, *pz;  ///< positions (velocity stage) or previous positions
  const Scalar* inverse_mass;
};

/// One side of a row in each lane: its particles, masses, centre, inertia pseudo-inverse, frame.
template <typename Lanes>
struct Side {
  using V = typename Lanes::value;
  using Index = typename Lanes::index;
  Index index[kJointRowSideParticles];
  Vec3<V> x[kJointRowSideParticles];  ///< positions (frames, levers)
  V mass[kJointRowSideParticles];
  Vec3<V> centre, u, v, w;
  Sym3<V> inverse_inertia;
};

// The frame (v, w, u) of particles x[0..3] (head, tail, F⁺, F⁻), the world's where `world`.
template <typename Lanes, typename Mask>
void side_frame(const Vec3<typename Lanes::value>* x, Mask world, Vec3<typename Lanes::value>& u, Vec3<typename Lanes::value>& v,
                Vec3<typename Lanes::value>& w) {
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(0), one = Lanes::broadcast(1);
  const Vec3<V> ex{one, zero, zero}, ez{zero, zero, one};
  u = normalized<Lanes>(x[0] - x[1], ez);
  Vec3<V> f = x[2] - x[3];
  f = f - dot(f, u) * u;
  v = normalized<Lanes>(f, ex);
  u = {Lanes::select(world, ez.x, u.x), Lanes::select(world, ez.y, u.y), Lanes::select(world, ez.z, u.z)};
  v = {Lanes::select(world, ex.x, v.x), Lanes::select(world, ex.y, v.y), Lanes::select(world, ex.z, v.z)};
  w = cross(u, v);
}

template <typename Lanes, typename Scalar>
Side<Lanes> load_side(const JointRowBatches<Scalar>& batches, std::size_t slot, int first, const Scalar* x, const Scalar* y,
                      const Scalar* z, const Scalar* inverse_mass, typename Lanes::value kind) {
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(0), one = Lanes::broadcast(1);
  Side<Lanes> side;
  V total = zero;
  Vec3<V> moment{zero, zero, zero};
  for (std::size_t k = 0; k < kJointRowSideParticles; ++k) {
    side.index[k] = Lanes::load(&batches.particle[first + k][slot]);
    side.x[k] = {Lanes::gather(x, side.index[k]), Lanes::gather(y, side.index[k]), Lanes::gather(z, side.index[k])};
    const V w_k = Lanes::gather(inverse_mass, side.index[k]);
    const auto movable = w_k > zero;
    side.mass[k] = Lanes::select(movable, one / Lanes::select(movable, w_k, one), zero);
    total = total + side.mass[k];
    moment = moment + side.mass[k] * side.x[k];
  }
  const auto has_mass = total > zero;
  const V inverse_total = Lanes::select(has_mass, one / Lanes::select(has_mass, total, one), zero);
  side.centre = inverse_total * moment;
  Sym3<V> inertia{zero, zero, zero, zero, zero, zero};
  V second_moment = zero;
  for (std::size_t k = 0; k < kJointRowSideParticles; ++k) {
    const Vec3<V> r = side.x[k] - side.centre;
    const V m = side.mass[k];
    const V r2 = dot(r, r);
    second_moment = second_moment + m * r2;
    inertia.xx = inertia.xx + m * (r2 - r.x * r.x), inertia.yy = inertia.yy + m * (r2 - r.y * r.y);
    inertia.zz = inertia.zz + m * (r2 - r.z * r.z);
    inertia.xy = inertia.xy - m * r.x * r.y, inertia.xz = inertia.xz - m * r.x * r.z, inertia.yz = inertia.yz - m * r.y * r.z;
  }
  const auto world = kind == Lanes::broadcast(Scalar(int(JointSide::world)));
  const auto framed = kind == Lanes::broadcast(Scalar(int(JointSide::framed)));
  side_frame<Lanes>(side.x, world, side.u, side.v, side.w);
  // Framed: the inverse by the adjugate. Stick: (E − u uᵀ)/S, S = Σ m|r|². World: 0.
  const Sym3<V>& I = inertia;
  const V c_xx = I.yy * I.zz - I.yz * I.yz, c_xy = I.xz * I.yz - I.xy * I.zz, c_xz = I.xy * I.yz - I.xz * I.yy;
  const V c_yy = I.xx * I.zz - I.xz * I.xz, c_yz = I.xy * I.xz - I.xx * I.yz, c_zz = I.xx * I.yy - I.xy * I.xy;
  const V determinant = I.xx * c_xx + I.xy * c_xy + I.xz * c_xz;
  const auto invertible = determinant > zero;
  const V inverse_determinant = Lanes::select(invertible, one / Lanes::select(invertible, determinant, one), zero);
  const auto stick_valid = second_moment > zero;
  const V inverse_moment = Lanes::select(stick_valid, one / Lanes::select(stick_valid, second_moment, one), zero);
  const Vec3<V>& u = side.u;
  const auto pick = [&](V framed_value, V stick_value) {
    return Lanes::select(world, zero, Lanes::select(framed, framed_value * inverse_determinant, stick_value * inverse_moment));
  };
  side.inverse_inertia = {pick(c_xx, one - u.x * u.x), pick(c_yy, one - u.y * u.y), pick(c_zz, one - u.z * u.z),
                          pick(c_xy, zero - u.x * u.y), pick(c_xz, zero - u.x * u.z), pick(c_yz, zero - u.y * u.z)};
  return side;
}

// The frame of one side at the previous positions (the substep's start).
template <typename Lanes, typename Scalar>
void start_frame(const Side<Lanes>& side, const JointFields<Scalar>& fields, typename Lanes::value kind,
                 Vec3<typename Lanes::value>& u, Vec3<typename Lanes::value>& v, Vec3<typename Lanes::value>& w) {
  using V = typename Lanes::value;
  Vec3<V> x[4];
  for (int k = 0; k < 4; ++k) {
    x[k] = {Lanes::gather(fields.px, side.index[k]), Lanes::gather(fields.py, side.index[k]), Lanes::gather(fields.pz, side.index[k])};
  }
  side_frame<Lanes>(x, kind == Lanes::broadcast(Scalar(int(JointSide::world))), u, v, w);
}

// A direction fixed in a side: coordinates (a, b, c) in its frame (v, w, u), read from
// direction[first..first+2].
template <typename Lanes, typename Scalar>
Vec3<typename Lanes::value> fixed_direction(const JointRowBatches<Scalar>& batches, std::size_t slot, int first,
                                            const Vec3<typename Lanes::value>& v, const Vec3<typename Lanes::value>& w,
                                            const Vec3<typename Lanes::value>& u) {
  const auto a = Lanes::load(&batches.direction[first][slot]), b = Lanes::load(&batches.direction[first + 1][slot]),
             c = Lanes::load(&batches.direction[first + 2][slot]);
  return a * v + b * w + c * u;
}

/// The measured coordinate of a row and the axis B turns about to increase it.
template <typename V>
struct Measure {
  V value;
  Vec3<V> axis;
};

// θ = atan2(y, x) and its gradient (x·∇y − y·∇x)/(x² + y²) from those of x and y.
template <typename Lanes>
Measure<typename Lanes::value> angle_of(typename Lanes::value y, typename Lanes::value x, const Vec3<typename Lanes::value>& gradient_y,
                                        const Vec3<typename Lanes::value>& gradient_x) {
  using V = typename Lanes::value;
  const V radius2 = x * x + y * y;
  const auto valid = radius2 > Lanes::broadcast(0);
  const V inverse = Lanes::select(valid, Lanes::broadcast(1) / Lanes::select(valid, radius2, Lanes::broadcast(1)), Lanes::broadcast(0));
  return {atan2_lanes<Lanes>(y, x), (inverse * x) * gradient_y - (inverse * y) * gradient_x};
}

// A hinge angle: `reference` r (fixed in A) against `e` (fixed in B) about `axis` d (fixed in
// A): θ = atan2((r × e)·d, r·e). Turning B by δ moves e by δ × e, so ∇x = e × r and
// ∇y = e × (d × r): the exact axis, d itself only while e ⟂ d.
template <typename Lanes>
Measure<typename Lanes::value> hinge_angle(const Vec3<typename Lanes::value>& reference, const Vec3<typename Lanes::value>& e,
                                           const Vec3<typename Lanes::value>& axis) {
  return angle_of<Lanes>(dot(cross(reference, e), axis), dot(reference, e), cross(e, cross(axis, reference)), cross(e, reference));
}

// The twist of B about its axis u against the swing-transported reference: d₂ (fixed in A, ⟂ c)
// carried by the shortest rotation taking the cone's axis c (carried by A) onto u,
// r = d₂ − k(c + u), k = (d₂·u)/D, D = 1 + c·u; θ = atan2((r × e)·u, r·e), e fixed in B.
// Its exact gradient (B turned by δ: u → u + δ × u, e → e + δ × e): with
// q = u × (d₂ − k c), dk = δ·q/D and dr = −dk (c + u) − k δ × u, so
//   ∇x = −((c + u)·e/D) q − k u × e + e × r,
//   ∇y = −((c + u)·(e × u)/D) q − k u × (e × u) + e × (u × r) + u × (r × e).
// It is u alone only while B has not swung; the rows and the trees used u, and the error in
// their projections fed energy into a swung joint at its twist limit (kernel/relaxation/README.md,
// "Limits with their exact gradients").
template <typename Lanes>
Measure<typename Lanes::value> twist_angle(const Vec3<typename Lanes::value>& cone, const Vec3<typename Lanes::value>& d2,
                                           const Vec3<typename Lanes::value>& e, const Vec3<typename Lanes::value>& u) {
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(0);
  const V denominator = Lanes::max(Lanes::broadcast(1) + dot(cone, u), Lanes::broadcast(1e-6));
  const V k = dot(d2, u) / denominator;
  const Vec3<V> sum = cone + u;
  const Vec3<V> reference = d2 - k * sum;
  const Vec3<V> q = cross(u, d2 - k * cone);
  const Vec3<V> e_cross_u = cross(e, u);
  const Vec3<V> gradient_x = (zero - dot(sum, e) / denominator) * q - k * cross(u, e) + cross(e, reference);
  const Vec3<V> gradient_y = (zero - dot(sum, e_cross_u) / denominator) * q - k * cross(u, e_cross_u) + cross(e, cross(u, reference)) +
                             cross(u, cross(reference, e));
  return angle_of<Lanes>(dot(cross(reference, e), u), dot(reference, e), gradient_y, gradient_x);
}

// The kind's coordinate from frames of A (va, wa, ua) and B (vb, wb, ub) (scalar kinds only).
template <typename Lanes, typename Scalar>
Measure<typename Lanes::value> measure(JointRowKind kind, const JointRowBatches<Scalar>& batches, std::size_t slot,
                                       const Vec3<typename Lanes::value>& va, const Vec3<typename Lanes::value>& wa,
                                       const Vec3<typename Lanes::value>& ua, const Vec3<typename Lanes::value>& vb,
                                       const Vec3<typename Lanes::value>& wb, const Vec3<typename Lanes::value>& ub) {
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(0);
  const Vec3<V> d1 = fixed_direction<Lanes>(batches, slot, 0, va, wa, ua);
  switch (kind) {
    case JointRowKind::align:
    case JointRowKind::swing: {
      const Vec3<V> e = kind == JointRowKind::swing ? ub : fixed_direction<Lanes>(batches, slot, 3, vb, wb, ub);
      const Vec3<V> s = cross(d1, e);
      const V sine = Lanes::sqrt(dot(s, s));
      return {atan2_lanes<Lanes>(sine, dot(d1, e)), normalized<Lanes>(s, {zero, zero, zero})};
    }
    case JointRowKind::perpendicular: {
      const Vec3<V> e = fixed_direction<Lanes>(batches, slot, 3, vb, wb, ub);
      return {dot(d1, e), cross(e, d1)};
    }
    case JointRowKind::twist:
      return twist_angle<Lanes>(d1, fixed_direction<Lanes>(batches, slot, 3, va, wa, ua), fixed_direction<Lanes>(batches, slot, 6, vb, wb, ub), ub);
    case JointRowKind::hinge:
    default:
      return hinge_angle<Lanes>(fixed_direction<Lanes>(batches, slot, 3, va, wa, ua), fixed_direction<Lanes>(batches, slot, 6, vb, wb, ub), d1);
  }
}

// r = ½ Σ t_i × b_i: B's frame (vb, wb, ub) against targets t_i = M e_i fixed in A (M from
// direction[0..8], A-frame coordinates), ≈ sin θ · n for B turned by θ about n past the target.
template <typename Lanes, typename Scalar>
Vec3<typename Lanes::value> orientation_error(const JointRowBatches<Scalar>& batches, std::size_t slot,
                                              const Vec3<typename Lanes::value>& va, const Vec3<typename Lanes::value>& wa,
                                              const Vec3<typename Lanes::value>& ua, const Vec3<typename Lanes::value>& vb,
                                              const Vec3<typename Lanes::value>& wb, const Vec3<typename Lanes::value>& ub) {
  using V = typename Lanes::value;
  const Vec3<V> t0 = fixed_direction<Lanes>(batches, slot, 0, va, wa, ua);
  const Vec3<V> t1 = fixed_direction<Lanes>(batches, slot, 3, va, wa, ua);
  const Vec3<V> t2 = fixed_direction<Lanes>(batches, slot, 6, va, wa, ua);
  return Lanes::broadcast(0.5) * (cross(t0, vb) + cross(t1, wb) + cross(t2, ub));
}

// B's start frame (vs, ws, us) carried into A's current frame by A's turn since the start:
// b_i ← R_A R_{A,s}ᵀ b_{i,s}. Returns r = ½ Σ t_i × b_i against those targets.
template <typename Lanes>
Vec3<typename Lanes::value> start_orientation_error(const Vec3<typename Lanes::value> (&a)[3], const Vec3<typename Lanes::value> (&a_start)[3],
                                                    const Vec3<typename Lanes::value> (&b)[3], const Vec3<typename Lanes::value> (&b_start)[3]) {
  using V = typename Lanes::value;
  Vec3<V> r{Lanes::broadcast(0), Lanes::broadcast(0), Lanes::broadcast(0)};
  for (int i = 0; i < 3; ++i) {
    const Vec3<V> target = dot(a_start[0], b_start[i]) * a[0] + dot(a_start[1], b_start[i]) * a[1] + dot(a_start[2], b_start[i]) * a[2];
    r = r + cross(target, b[i]);
  }
  return Lanes::broadcast(0.5) * r;
}

/// What a block's projection does: the position stage (XPBD) or the rattle rule's velocity
/// stage (removes the rate of rigid rows and of limits that are reached).
enum class Stage : std::uint8_t { positions, velocities };

/// Projects slots [begin, end) (whole blocks of one kind, or overflow slots with Lanes of one
/// lane) in place. `h` is the substep (s). Returns the largest particle displacement (m) or
/// velocity change (m/s).
template <typename Lanes, Stage kStage, typename Scalar>
Scalar project_joint_rows(JointRowBatches<Scalar>& batches, JointRowKind kind, std::size_t begin, std::size_t end,
                          const JointFields<Scalar>& fields, Scalar h) {
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(0), one = Lanes::broadcast(1);
  const V step = Lanes::broadcast(h);
  V largest = zero;
  // Positions the frames and levers are taken from: the moved field in the position stage.
  const Scalar* px = kStage == Stage::positions ? fields.x : fields.px;
  const Scalar* py = kStage == Stage::positions ? fields.y : fields.py;
  const Scalar* pz = kStage == Stage::positions ? fields.z : fields.pz;
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    if (kind == JointRowKind::point) {
      // C = Σ c_k x_k (positions or velocities), linear.
      typename Lanes::index index[kJointRowParticles];
      Vec3<V> x[kJointRowParticles];
      V c[kJointRowParticles], w[kJointRowParticles];
      Vec3<V> error{zero, zero, zero};
      V denominator = zero;
      for (std::size_t k = 0; k < kJointRowParticles; ++k) {
        index[k] = Lanes::load(&batches.particle[k][slot]);
        x[k] = {Lanes::gather(fields.x, index[k]), Lanes::gather(fields.y, index[k]), Lanes::gather(fields.z, index[k])};
        c[k] = Lanes::load(&batches.direction[k][slot]);
        w[k] = Lanes::gather(fields.inverse_mass, index[k]);
        error = error + c[k] * x[k];
        denominator = denominator + c[k] * c[k] * w[k];
      }
      const auto valid = denominator > zero;
      const V scale = Lanes::select(valid, one / Lanes::select(valid, denominator, one), zero);
      for (std::size_t k = 0; k < kJointRowParticles; ++k) {
        const V move = zero - c[k] * w[k] * scale;
        const Vec3<V> delta = move * error;
        x[k] = x[k] + delta;
        largest = Lanes::max(largest, Lanes::sqrt(dot(delta, delta)));
      }
      // Written back in reverse so that a particle named twice (never, but the null particle)
      // keeps one consistent value. A place no lane moves is not written: the null particle
      // stands in every empty place, and threads writing its cache line would contend for it.
      for (std::size_t k = kJointRowParticles; k-- > 0;) {
        if (!Lanes::any(w[k] > zero)) continue;
        Lanes::scatter(x[k].x, fields.x, index[k]), Lanes::scatter(x[k].y, fields.y, index[k]), Lanes::scatter(x[k].z, fields.z, index[k]);
      }
      continue;
    }
    const V kind_a = Lanes::load(&batches.side_a[slot]), kind_b = Lanes::load(&batches.side_b[slot]);
    Side<Lanes> a = load_side<Lanes>(batches, slot, 0, px, py, pz, fields.inverse_mass, kind_a);
    Side<Lanes> b = load_side<Lanes>(batches, slot, static_cast<int>(kJointRowSideParticles), px, py, pz, fields.inverse_mass, kind_b);
    const V stiffness = Lanes::load(&batches.stiffness[slot]), damping = Lanes::load(&batches.damping[slot]);
    const V lower = Lanes::load(&batches.lower[slot]), upper = Lanes::load(&batches.upper[slot]);
    const V friction = Lanes::load(&batches.friction[slot]);
    // The drive: k_eff = k + c/h; a rigid row (k = c = 0) keeps its stored blend.
    const V damping_rate = damping / step;
    const V k_effective = stiffness + damping_rate;
    const auto compliant = k_effective > zero;
    const V blend = Lanes::select(compliant, damping_rate / Lanes::select(compliant, k_effective, one), Lanes::load(&batches.blend[slot]));
    const V compliance = Lanes::select(compliant, one / (Lanes::select(compliant, k_effective, one) * step * step), zero);
    const bool uses_start = Lanes::any(blend > zero);
    V value;
    Vec3<V> axis;
    if (kind == JointRowKind::orientation) {
      Vec3<V> r = orientation_error<Lanes>(batches, slot, a.v, a.w, a.u, b.v, b.w, b.u);
      if (uses_start) {
        Vec3<V> sa[3], sb[3];
        start_frame<Lanes>(a, fields, kind_a, sa[2], sa[0], sa[1]);
        start_frame<Lanes>(b, fields, kind_b, sb[2], sb[0], sb[1]);
        const Vec3<V> fa[3] = {a.v, a.w, a.u}, fb[3] = {b.v, b.w, b.u};
        const Vec3<V> target_rate = fixed_direction<Lanes>(batches, slot, 9, a.v, a.w, a.u);  // ω_t, A-frame coordinates
        const Vec3<V> from_start = start_orientation_error<Lanes>(fa, sa, fb, sb) - step * target_rate;
        r = (one - blend) * r + blend * from_start;
      }
      value = Lanes::sqrt(dot(r, r));
      axis = normalized<Lanes>(r, {zero, zero, zero});
    } else {
      const Measure<V> m = measure<Lanes>(kind, batches, slot, a.v, a.w, a.u, b.v, b.w, b.u);
      V target = Lanes::load(&batches.target[slot]);
      if (uses_start) {
        Vec3<V> sa[3], sb[3];
        start_frame<Lanes>(a, fields, kind_a, sa[2], sa[0], sa[1]);
        start_frame<Lanes>(b, fields, kind_b, sb[2], sb[0], sb[1]);
        const V start = measure<Lanes>(kind, batches, slot, sa[0], sa[1], sa[2], sb[0], sb[1], sb[2]).value;
        target = (one - blend) * target + blend * (start + step * Lanes::load(&batches.target_velocity[slot]));
      }
      value = m.value - target;
      axis = m.axis;
    }
    const V outside = value - Lanes::max(lower, min_lanes<Lanes>(value, upper));
    const Vec3<V> turn_a = a.inverse_inertia * axis, turn_b = b.inverse_inertia * axis;
    const V inverse_mass = dot(axis, turn_a) + dot(axis, turn_b);
    V delta;
    if constexpr (kStage == Stage::positions) {
      const V lambda = Lanes::load(&batches.lambda[slot]);
      const V denominator = inverse_mass + compliance;
      const auto valid = denominator > zero;
      delta = Lanes::select(valid, (zero - outside - compliance * lambda) / Lanes::select(valid, denominator, one), zero);
      // Friction rows clamp the accumulated multiplier (a torque bound times h²).
      const V bound = friction * step * step;
      const auto bounded = friction > zero;
      const V clamped = Lanes::max(zero - bound, min_lanes<Lanes>(lambda + delta, bound));
      delta = Lanes::select(bounded, clamped - lambda, delta);
      Lanes::store(lambda + delta, &batches.lambda[slot]);
    } else {
      // Velocity stage: rigid rows (no spring, no damper, no start term) and limits that hold.
      Vec3<V> momentum_a{zero, zero, zero}, momentum_b{zero, zero, zero};
      for (std::size_t k = 0; k < kJointRowSideParticles; ++k) {
        const Vec3<V> va{Lanes::gather(fields.x, a.index[k]), Lanes::gather(fields.y, a.index[k]), Lanes::gather(fields.z, a.index[k])};
        const Vec3<V> vb{Lanes::gather(fields.x, b.index[k]), Lanes::gather(fields.y, b.index[k]), Lanes::gather(fields.z, b.index[k])};
        momentum_a = momentum_a + a.mass[k] * cross(a.x[k] - a.centre, va);
        momentum_b = momentum_b + b.mass[k] * cross(b.x[k] - b.centre, vb);
      }
      const V rate = dot(axis, b.inverse_inertia * momentum_b) - dot(axis, a.inverse_inertia * momentum_a);
      const auto rigid = (k_effective == zero) & (blend == zero) & (friction == zero);
      const auto equality = lower == upper;
      // A limit holds only where it is reached and the motion goes further out.
      const auto reached = (outside * rate > zero) | equality;
      const auto active = rigid & reached & (inverse_mass > zero);
      delta = Lanes::select(active, (zero - rate) / Lanes::select(active, inverse_mass, one), zero);
    }
    const Vec3<V> spin_a = (zero - delta) * turn_a, spin_b = delta * turn_b;
    for (Side<Lanes>* side : {&a, &b}) {
      const Vec3<V>& spin = side == &a ? spin_a : spin_b;
      for (std::size_t k = 0; k < kJointRowSideParticles; ++k) {
        const auto movable = side->mass[k] > zero;
        if (!Lanes::any(movable)) continue;  // an empty place in every lane: the null particle, not written
        const Vec3<V> move = cross(spin, side->x[k] - side->centre);
        const Vec3<V> masked{Lanes::select(movable, move.x, zero), Lanes::select(movable, move.y, zero), Lanes::select(movable, move.z, zero)};
        largest = Lanes::max(largest, Lanes::sqrt(dot(masked, masked)));
        const auto& i = side->index[k];
        Lanes::scatter(Lanes::gather(fields.x, i) + masked.x, fields.x, i);
        Lanes::scatter(Lanes::gather(fields.y, i) + masked.y, fields.y, i);
        Lanes::scatter(Lanes::gather(fields.z, i) + masked.z, fields.z, i);
      }
    }
  }
  return Lanes::reduce_max(largest);
}

}  // namespace limber::joint_projection
