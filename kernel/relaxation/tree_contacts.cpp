#include "limber/kernel/relaxation/tree_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/relaxation/joint_trees.hpp"
#include "limber/kernel/relaxation/tree_packs.hpp"

namespace limber {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using PointJacobian = Eigen::Matrix<double, 3, 6>;

// A contact that wanted less than this share of the largest push of its tree is lifted by its
// neighbours' pushes, which is no overshoot (tree_contact_overshoot).
constexpr double kSignificantPush = 0.1;

std::size_t component_of(const JointTrees& trees, std::int32_t limb) {
  return static_cast<std::size_t>(trees.component_of_limb[static_cast<std::size_t>(limb)]);
}

// The tree limb of a contact side's particle whose island is awake, −1 if none (static, a
// particle outside the trees, or asleep: then the side stays where it is).
template <typename Scalar>
std::int32_t awake_tree_limb(const VerletState<Scalar>& state, std::uint32_t particle) {
  const JointTrees& trees = state.plan.joint_trees;
  const std::int32_t limb = trees.limb_of_particle[particle];
  if (limb < 0) return -1;
  return state.islands[trees.component_island[component_of(trees, limb)]].sleeping ? -1 : limb;
}

// Whether a row's side s (places 2s, 2s + 1) moves anything: c ≠ 0 on a movable particle.
template <typename Scalar>
bool side_moves(const VerletState<Scalar>& state, const ContactRow& row, std::size_t s) {
  for (std::size_t k = s * kContactRowSideParticles; k < (s + 1) * kContactRowSideParticles; ++k) {
    if (row.coefficient[k] != 0 && state.particles.inverse_mass[row.particle[k]] > 0) return true;
  }
  return false;
}

// A side's point map P = [σE, −[ρ]×] (its point moves by σΔp + Δφ × ρ when its limb moves by
// (Δp, Δφ)) and its normal row J = nᵀP.
void set_side(TreeContact& contact, std::size_t s, double sigma, const Eigen::Vector3d& lever) {
  PointJacobian& p = contact.point_jacobian[s];
  p.leftCols<3>() = sigma * Eigen::Matrix3d::Identity();
  p.rightCols<3>() << 0, lever.z(), -lever.y(), -lever.z(), 0, lever.x(), lever.y(), -lever.x(), 0;
  contact.normal_jacobian[s] = p.transpose() * contact.normal;
}

// A contact at the current positions (its limbs' centres as the trees loaded them): its normal,
// separation C (m, < 0 overlapping, less what it may keep of an overlap it began with), slip since
// the substep began (its point: Σ c_k x_k for a row, the feature's particle for a plane) and each
// side's maps, into the contact.
template <typename Scalar>
void evaluate(const VerletState<Scalar>& state, TreeContact& contact) {
  const JointTrees& trees = state.plan.joint_trees;
  const auto position = [&](std::uint32_t p) -> Eigen::Vector3d { return state.particles.position(p).template cast<double>(); };
  if (contact.source == TreeContact::Source::row) {
    const ContactRow& row = state.contact_rows.rows[contact.index];
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < kContactRowParticles; ++k) {
      if (row.coefficient[k] != 0) point += row.coefficient[k] * position(row.particle[k]);
    }
    contact.normal = row.normal, contact.separation = row.normal.dot(point) - row.offset, contact.slip = point - contact.start;
    for (std::size_t s = 0; s < 2; ++s) {
      if (contact.limb[s] < 0) continue;
      const Eigen::Vector3d& centre = trees.centre[static_cast<std::size_t>(contact.limb[s])];
      double sigma = 0;
      Eigen::Vector3d lever = Eigen::Vector3d::Zero();
      for (std::size_t k = s * kContactRowSideParticles; k < (s + 1) * kContactRowSideParticles; ++k) {
        sigma += row.coefficient[k], lever += row.coefficient[k] * (position(row.particle[k]) - centre);
      }
      set_side(contact, s, sigma, lever);
    }
    return;
  }
  const PlaneContact& plane_contact = state.plane_contacts[contact.index];
  const ContactFeature& feature = state.features[plane_contact.feature];
  const Plane& plane = state.planes[plane_contact.plane];
  const Eigen::Vector3d point = position(feature.particle), partner = position(feature.axis_partner);
  const PlaneFeatureConstraint constraint =
      plane_feature_constraint(plane.normal, plane.offset, point, partner, feature.radius, feature.is_disk, feature.at_centre);
  const Eigen::Vector3d x = feature.at_centre ? Eigen::Vector3d(0.5 * (point + partner)) : point;  // where it touches, less its radius
  const Eigen::Vector3d& centre = trees.centre[static_cast<std::size_t>(contact.limb[0])];
  contact.normal = plane.normal, contact.slip = x - contact.start;
  contact.separation = constraint.separation - allowed_separation(plane_contact.start_separation, trees.recovery);
  set_side(contact, 0, 1.0, x - centre);
  // The rim's own gradient (a tipped disk's lowest point moves as the limb turns): J = Σ_k [g_k; r_k × g_k].
  Vector6& j = contact.normal_jacobian[0];
  j.head<3>() = constraint.gradient_point, j.tail<3>() = (point - centre).cross(constraint.gradient_point);
  if (feature.axis_partner != feature.particle) {
    j.head<3>() += constraint.gradient_partner, j.tail<3>() += (partner - centre).cross(constraint.gradient_partner);
  }
}

// A contact's mobilities, the round's, from its acting sides' blocks of their trees' inverses Z:
// along n, a_s = J_s Z_s J_sᵀ (a loop's exact, from take_loop_mobilities); at its point,
// W_s = P_s Z_s P_sᵀ (a loop's without its sides' coupling).
void take_mobilities(const JointTrees& trees, TreeContact& contact) {
  for (std::size_t s = 0; s < 2; ++s) {
    contact.normal_mobility[s] = 0, contact.point_mobility[s].setZero();
    if (!contact.acting[s]) continue;
    const Eigen::Matrix<double, 6, 6>& z = trees.mobility[static_cast<std::size_t>(contact.limb[s])];
    contact.normal_mobility[s] = contact.loop ? contact.loop_mobility[s] : contact.normal_jacobian[s].dot(z * contact.normal_jacobian[s]);
    contact.point_mobility[s] = contact.point_jacobian[s] * z * contact.point_jacobian[s].transpose();
  }
}

// The position impulses that close a separation C and undo a slip, as the contact rows take them
// (contact_projection.hpp) with the trees' mobilities: the push λ = −C/a_n where C < 0, and the
// friction impulse accumulated over the substep, clamped to μ times the push so far, with
// a_t = ½(tr W − nᵀWn). Into contact.push and contact.slide.
// Within a round's iterations the pushes are Jacobi's on the round's linearization: a later
// iteration may take back what an earlier one of the round pushed (its round total stays ≥ 0),
// which is how the overshoot of contacts pushing one tree together is undone.
void take_impulses(TreeContact& contact, double separation, Eigen::Vector3d slip) {
  contact.push = 0, contact.slide.setZero();
  const double normal_mobility = contact.normal_mobility[0] + contact.normal_mobility[1];
  if (!(normal_mobility > 0)) return;
  contact.push = std::max(-separation / normal_mobility, -contact.round_push);
  const Eigen::Vector3d& n = contact.normal;
  slip -= n.dot(slip) * n;
  const Eigen::Matrix3d point = contact.point_mobility[0] + contact.point_mobility[1];
  const double tangent_mobility = 0.5 * (point.trace() - n.dot(point * n));
  const Eigen::Vector3d taken = contact.tangent + contact.round_slide;
  Eigen::Vector3d total = taken;
  if (tangent_mobility > 0) total -= slip / tangent_mobility;
  const double size = total.norm(), grip = contact.friction * (contact.lambda + contact.round_push + contact.push);
  if (size > grip) total *= grip / size;
  contact.slide = total - taken;
}

// The loads of the contact's impulses on its acting sides' limbs.
void set_loads(TreeContact& contact) {
  for (std::size_t s = 0; s < 2; ++s) {
    contact.load[s] = contact.acting[s] ? Vector6(contact.normal_jacobian[s] * contact.push + contact.point_jacobian[s].transpose() * contact.slide)
                                        : Vector6::Zero();
  }
}

// Calls visit(contact, side, limb) for each acting side of `component`'s contacts in it (both of a
// loop's, once each: gather_tree_contacts lists a loop once).
template <typename Visit>
void for_each_side(const JointTrees& trees, std::uint32_t component, Visit&& visit) {
  for (const std::uint32_t c : trees.component_contacts.row(component)) {
    const TreeContact& contact = trees.contacts[c];
    for (std::size_t s = 0; s < 2; ++s) {
      if (contact.acting[s] && component_of(trees, contact.limb[s]) == component) visit(contact, s, static_cast<std::size_t>(contact.limb[s]));
    }
  }
}

}  // namespace

template <typename Scalar>
bool held_by_joint_trees(const VerletState<Scalar>& state, const ContactRow& row) {
  if (!state.plan.joint_trees.with_contacts) return false;
  bool some = false;
  for (std::size_t s = 0; s < 2; ++s) {
    if (!side_moves(state, row, s)) continue;
    for (std::size_t k = s * kContactRowSideParticles; k < (s + 1) * kContactRowSideParticles; ++k) {
      if (row.coefficient[k] != 0 && awake_tree_limb(state, row.particle[k]) < 0) return false;
    }
    some = true;
  }
  return some;
}

template <typename Scalar>
void gather_tree_contacts(VerletState<Scalar>& state, double h) {
  JointTrees& trees = state.plan.joint_trees;
  trees.contacts.clear(), trees.contact_pairs.clear();
  if (!trees.with_contacts) return;
  trees.recovery = state.settings.contact_recovery_speed * h;
  // Room for every row and plane contact the substep could hold: allocates only when those grew.
  const std::size_t room = state.contact_rows.rows.capacity() + state.plane_contacts.capacity();
  if (trees.contacts.capacity() < room) {
    trees.contacts.reserve(room), trees.contact_pairs.reserve(2 * room), trees.component_contacts.entries.reserve(2 * room);
  }
  const auto start_of = [&](std::uint32_t p) -> Eigen::Vector3d { return state.particles.previous(p).template cast<double>(); };
  const auto& rows = state.contact_rows.rows;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const ContactRow& row = rows[r];
    if (!held_by_joint_trees(state, row)) continue;
    TreeContact contact;
    contact.source = TreeContact::Source::row, contact.index = static_cast<std::uint32_t>(r), contact.friction = row.friction;
    for (std::size_t k = 0; k < kContactRowParticles; ++k) {
      if (row.coefficient[k] != 0) contact.start += row.coefficient[k] * start_of(row.particle[k]);
    }
    for (std::size_t s = 0; s < 2; ++s) {
      if (side_moves(state, row, s)) contact.limb[s] = trees.limb_of_particle[row.particle[s * kContactRowSideParticles]];
    }
    contact.loop = contact.limb[0] >= 0 && contact.limb[1] >= 0 && component_of(trees, contact.limb[0]) == component_of(trees, contact.limb[1]);
    trees.contacts.push_back(contact);
  }
  for (std::size_t c = 0; c < state.plane_contacts.size(); ++c) {
    PlaneContact& plane_contact = state.plane_contacts[c];
    const ContactFeature& feature = state.features[plane_contact.feature];
    const std::int32_t limb = awake_tree_limb(state, feature.particle);
    plane_contact.held_by_trees = limb >= 0 && trees.limb_of_particle[feature.axis_partner] == limb;
    if (!plane_contact.held_by_trees) continue;
    TreeContact contact;
    contact.source = TreeContact::Source::plane, contact.index = static_cast<std::uint32_t>(c);
    contact.friction = state.planes[plane_contact.plane].friction;
    contact.start = feature.at_centre ? Eigen::Vector3d(0.5 * (start_of(feature.particle) + start_of(feature.axis_partner))) : start_of(feature.particle);
    contact.limb[0] = limb;
    trees.contacts.push_back(contact);
  }
  // Each contact once under each component it has a side in: a loop (both sides in one tree) is
  // listed once, or for_each_side would visit its sides twice and load its tree twice over.
  for (std::size_t c = 0; c < trees.contacts.size(); ++c) {
    const TreeContact& contact = trees.contacts[c];
    for (std::size_t s = 0; s < 2; ++s) {
      if (contact.limb[s] < 0) continue;
      if (s == 1 && contact.loop) continue;
      trees.contact_pairs.emplace_back(static_cast<std::uint32_t>(component_of(trees, contact.limb[s])), static_cast<std::uint32_t>(c));
    }
  }
  group_by_row_into(trees.component_contacts, trees.settled.size(), trees.contact_pairs);
}

template <typename Scalar>
void take_loop_mobilities(VerletState<Scalar>& state, TreePack<Scalar>& pack, const LaneMask& lanes) {
  constexpr std::size_t kLanes = TreePack<Scalar>::kLanes;
  JointTrees& trees = state.plan.joint_trees;
  std::array<std::size_t, kLanes> next{};  // per lane: its next contact in its component's row
  std::array<PathLoad, kLanes> paths;
  std::array<TreeContact*, kLanes> taken{};
  for (;;) {
    bool any = false;
    for (std::size_t lane = 0; lane < kLanes; ++lane) {
      taken[lane] = nullptr, paths[lane].limbs = {-1, -1};
      if (!lanes[lane]) continue;
      const auto component = static_cast<std::uint32_t>(pack.component[lane]);
      const auto row = trees.component_contacts.row(component);
      while (next[lane] < row.size() && !trees.contacts[row[next[lane]]].loop) ++next[lane];
      if (next[lane] == row.size()) continue;
      TreeContact& contact = trees.contacts[row[next[lane]++]];
      evaluate(state, contact);
      // The paths from its two limbs to the root carry the response.
      paths[lane].limbs = contact.limb, paths[lane].load = contact.normal_jacobian;
      taken[lane] = &contact, any = true;
      ++trees.counts[component].path_solves;
    }
    if (!any) return;
    solve_pack_paths(trees, pack, std::span<PathLoad, kLanes>(paths));
    for (std::size_t lane = 0; lane < kLanes; ++lane) {
      if (!taken[lane]) continue;
      for (std::size_t s = 0; s < 2; ++s) taken[lane]->loop_mobility[s] = taken[lane]->normal_jacobian[s].dot(paths[lane].motion[s]);
    }
  }
}

namespace {

// The impulses the last iteration took, at the larger of its acting sides' components' scales,
// join the round's.
void keep_iteration_impulses(const JointTrees& trees, TreeContact& contact) {
  double scale = 1;
  for (std::size_t s = 0; s < 2; ++s) {
    if (contact.acting[s]) scale = std::max(scale, trees.load_scale[component_of(trees, contact.limb[s])]);
  }
  contact.round_push += contact.push / scale, contact.round_slide += contact.slide / scale;
  contact.push = 0, contact.slide.setZero();
}

// One contact's impulses and loads in an iteration (tree_contact_impulses).
template <typename Scalar>
void contact_iteration(const VerletState<Scalar>& state, JointTrees& trees, TreeContact& contact, bool first) {
  if (first) {
    contact.push = 0, contact.slide.setZero();
    for (std::size_t s = 0; s < 2; ++s) contact.acting[s] = contact.limb[s] >= 0 && !trees.settled[component_of(trees, contact.limb[s])];
  } else {
    keep_iteration_impulses(trees, contact);
  }
  if (!contact.acting[0] && !contact.acting[1]) return;
  if (first) {
    // A loop was measured at these positions in stage 1, with its component's limbs loaded.
    if (!contact.loop) evaluate(state, contact);
    take_mobilities(trees, contact);
  }
  // Its separation and slip once both sides' joint steps and the round's contact motion so far
  // have moved them.
  double separation = contact.separation;
  Eigen::Vector3d slip = contact.slip;
  for (std::size_t s = 0; s < 2; ++s) {
    if (!contact.acting[s]) continue;
    const auto limb = static_cast<std::size_t>(contact.limb[s]);
    const Vector6 motion = trees.joint_motion[limb] + trees.load_motion[limb];
    separation += contact.normal_jacobian[s].dot(motion), slip += contact.point_jacobian[s] * motion;
  }
  take_impulses(contact, separation, slip);
  set_loads(contact);
  for (std::size_t s = 0; s < 2; ++s) {
    contact.wanted[s] = contact.push * contact.normal_mobility[s];
    const Eigen::Vector3d slide = contact.point_mobility[s] * contact.slide;
    contact.wanted_slide[s] = slide - contact.normal.dot(slide) * contact.normal;
  }
}

// Contacts a task of the impulses' stage takes on the relaxation's threads.
constexpr std::size_t kContactsPerTask = 64;

template <typename Scalar>
struct ImpulseStage {
  VerletState<Scalar>* state;
  bool first;
  static double run(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const ImpulseStage*>(context);
    JointTrees& trees = stage.state->plan.joint_trees;
    const std::size_t end = std::min(trees.contacts.size(), (task + 1) * kContactsPerTask);
    for (std::size_t c = task * kContactsPerTask; c < end; ++c) contact_iteration(*stage.state, trees, trees.contacts[c], stage.first);
    return 0;
  }
};

}  // namespace

template <typename Scalar>
void tree_contact_impulses(VerletState<Scalar>& state, bool first) {
  // Each contact writes only its own fields and reads the trees' stage-1 and stage-3 results:
  // any split over the threads gives the same bits.
  const ImpulseStage<Scalar> stage{&state, first};
  const std::size_t tasks = (state.plan.joint_trees.contacts.size() + kContactsPerTask - 1) / kContactsPerTask;
  if (joint_trees_on_threads(state.plan) && tasks > 1) {
    state.plan.runner->run(tasks, &ImpulseStage<Scalar>::run, &stage);
    return;
  }
  for (std::size_t task = 0; task < tasks; ++task) ImpulseStage<Scalar>::run(&stage, task);
}

bool add_tree_contact_loads(JointTrees& trees, std::uint32_t component) {
  bool any = false;
  for_each_side(trees, component, [&](const TreeContact& contact, std::size_t s, std::size_t limb) {
    trees.elimination.work(limb) += contact.load[s];
    any = any || contact.push > 0 || contact.slide.squaredNorm() > 0;
  });
  return any;
}

double tree_contact_overshoot(const JointTrees& trees, std::uint32_t component) {
  double most_wanted = 0;
  for_each_side(trees, component, [&](const TreeContact& contact, std::size_t s, std::size_t) {
    most_wanted = std::max({most_wanted, std::abs(contact.wanted[s]), contact.wanted_slide[s].norm()});
  });
  double largest = 1;
  for_each_side(trees, component, [&](const TreeContact& contact, std::size_t s, std::size_t limb) {
    const Eigen::Matrix<double, 6, 1>& motion = trees.elimination.work(limb);
    if (std::abs(contact.wanted[s]) > kSignificantPush * most_wanted) {
      largest = std::max(largest, contact.normal_jacobian[s].dot(motion) / contact.wanted[s]);
    }
    const double slide = contact.wanted_slide[s].squaredNorm();
    if (slide > kSignificantPush * kSignificantPush * most_wanted * most_wanted) {
      largest = std::max(largest, contact.wanted_slide[s].dot(contact.point_jacobian[s] * motion) / slide);
    }
  });
  return largest;
}

void end_tree_contact_round(JointTrees& trees) {
  for (TreeContact& contact : trees.contacts) {
    keep_iteration_impulses(trees, contact);
    contact.lambda += contact.round_push, contact.tangent += contact.round_slide;
    contact.round_push = 0, contact.round_slide.setZero();
  }
}

int tree_contact_rows_pushed(const JointTrees& trees) {
  return static_cast<int>(std::count_if(trees.contacts.begin(), trees.contacts.end(),
                                        [](const TreeContact& c) { return c.source == TreeContact::Source::row && c.lambda > 0; }));
}

#define LIMBER_INSTANTIATE(Scalar)                                                           \
  template bool held_by_joint_trees<Scalar>(const VerletState<Scalar>&, const ContactRow&); \
  template void gather_tree_contacts<Scalar>(VerletState<Scalar>&, double);                  \
  template void take_loop_mobilities<Scalar>(VerletState<Scalar>&, TreePack<Scalar>&, const LaneMask&); \
  template void tree_contact_impulses<Scalar>(VerletState<Scalar>&, bool);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
