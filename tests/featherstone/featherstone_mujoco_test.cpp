// limber's articulated-body algorithm against MuJoCo 2.2.2 (Debian's libmujoco-dev): the same
// random trees, written as MJCF, give the same joint accelerations to 1e-9 (relative).
//
// Convention mapping (MuJoCo's, from its documentation and engine_core_smooth.c):
// - <body pos quat>: the child body frame in the parent's at qpos0 = limber's X_tree (position r,
//   orientation R, E = Rᵀ). Joints sit at the body origin (joint pos = 0), so limber's joint frame
//   is the child frame at q = 0 in both.
// - hinge / slide: `axis` in the child body frame; qpos is the angle / displacement, qvel its
//   rate, qfrc_applied the torque / force: limber's revolute / prismatic, one to one.
// - ball: qpos is the quaternion (w, x, y, z) of the child relative to the parent (child → parent
//   rotation), qvel the child's angular velocity relative to its parent in the child frame, qacc
//   its rate, qfrc_applied the torque in the child frame: limber's spherical, one to one.
// - no joint: the body is welded to its parent: limber's fixed.
// - free (top-level bodies only; body pos/quat are ignored, qpos sets the pose): qpos = (p, quat)
//   as limber's floating. qvel = (ṗ in the world frame, ω in the body frame), whereas limber's
//   v = (ω, Rᵀ ṗ), both in the body frame. So qvel = (R v_lin, ω), qfrc_applied = (R f, n) (the
//   same power), and, differentiating R v_lin with Ṙ = R [ω]×,
//   qacc = (R (v̇_lin + ω × v_lin), ω̇).
// - gravity: <option gravity>, the same world vector in both. No geoms, contacts disabled, no
//   damping, armature, friction loss or springs, so qacc = M⁻¹(qfrc_applied − qfrc_bias).
#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>

#include "limber/kernel/featherstone/dynamics.hpp"
#include "tests/featherstone/random_trees.hpp"

namespace limber {
namespace {

using testing::random_positions;
using testing::random_tree;
using testing::random_vector;
using testing::RandomTreeOptions;

std::string numbers(std::initializer_list<double> values) {
  std::ostringstream out;
  out.precision(17);
  const char* separator = "";
  for (double value : values) out << separator << value, separator = " ";
  return out.str();
}

std::string numbers(const Eigen::Vector3d& v) { return numbers({v.x(), v.y(), v.z()}); }
std::string numbers(const Eigen::Quaterniond& q) { return numbers({q.w(), q.x(), q.y(), q.z()}); }

// The tree as MJCF: one <body> per body, nested as in the tree, named "b<index>"; each body's
// inertia written as fullinertia, or (when `diagonal` says so) as principal moments and frame.
class MjcfWriter {
 public:
  MjcfWriter(const ArticulatedTree& tree, const std::vector<bool>& diagonal) : tree_(tree), diagonal_(diagonal) {}

  std::string write(const Eigen::Vector3d& gravity) {
    out_ << "<mujoco model=\"random_tree\">\n"
         << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
         << "  <option gravity=\"" << numbers(gravity) << "\" timestep=\"0.001\">\n"
         << "    <flag contact=\"disable\"/>\n"
         << "  </option>\n"
         << "  <worldbody>\n";
    write_children(-1, 2);
    out_ << "  </worldbody>\n</mujoco>\n";
    return out_.str();
  }

 private:
  void write_children(int parent, int depth) {
    for (int i = 0; i < tree_.body_count(); ++i) {
      if (tree_.body(i).parent == parent) write_body(i, depth);
    }
  }

  void write_body(int index, int depth) {
    const ArticulatedBody& body = tree_.body(index);
    const std::string indent(static_cast<std::size_t>(2 * depth), ' ');
    const Eigen::Quaterniond orientation(body.tree_transform.rotation.transpose());  // R = Eᵀ
    out_ << indent << "<body name=\"b" << index << "\" pos=\"" << numbers(body.tree_transform.translation) << "\" quat=\""
         << numbers(orientation) << "\">\n";
    switch (body.joint) {
      case ArticulatedJoint::revolute:
        out_ << indent << "  <joint type=\"hinge\" pos=\"0 0 0\" axis=\"" << numbers(body.joint_axis) << "\"/>\n";
        break;
      case ArticulatedJoint::prismatic:
        out_ << indent << "  <joint type=\"slide\" pos=\"0 0 0\" axis=\"" << numbers(body.joint_axis) << "\"/>\n";
        break;
      case ArticulatedJoint::spherical: out_ << indent << "  <joint type=\"ball\" pos=\"0 0 0\"/>\n"; break;
      case ArticulatedJoint::floating: out_ << indent << "  <freejoint/>\n"; break;
      case ArticulatedJoint::fixed: break;
    }
    const Eigen::Matrix3d about_centre = body.inertia.inertia_about_centre_of_mass();
    out_ << indent << "  <inertial pos=\"" << numbers(body.inertia.centre_of_mass()) << "\" mass=\"" << numbers({body.inertia.mass}) << "\" ";
    if (diagonal_[static_cast<std::size_t>(index)]) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal(about_centre);
      Eigen::Matrix3d axes = principal.eigenvectors();
      if (axes.determinant() < 0) axes.col(2) *= -1;
      out_ << "quat=\"" << numbers(Eigen::Quaterniond(axes)) << "\" diaginertia=\"" << numbers(principal.eigenvalues()) << "\"/>\n";
    } else {
      out_ << "fullinertia=\""
           << numbers({about_centre(0, 0), about_centre(1, 1), about_centre(2, 2), about_centre(0, 1), about_centre(0, 2), about_centre(1, 2)})
           << "\"/>\n";
    }
    write_children(index, depth + 1);
    out_ << indent << "</body>\n";
  }

  const ArticulatedTree& tree_;
  const std::vector<bool>& diagonal_;
  std::ostringstream out_;
};

// Loads MJCF text through MuJoCo's virtual file system (no temporary file).
struct MujocoModel {
  mjModel* model = nullptr;
  mjData* data = nullptr;
  std::string error;

  explicit MujocoModel(const std::string& text) {
    auto files = std::make_unique<mjVFS>();  // ~2 MB: not on the stack
    mj_defaultVFS(files.get());
    mj_makeEmptyFileVFS(files.get(), "tree.xml", static_cast<int>(text.size()));
    const int file = mj_findFileVFS(files.get(), "tree.xml");
    std::copy(text.begin(), text.end(), static_cast<char*>(files->filedata[file]));
    char message[1000] = "";
    model = mj_loadXML("tree.xml", files.get(), message, sizeof message);
    mj_deleteVFS(files.get());
    error = message;
    if (model) data = mj_makeData(model);
  }
  ~MujocoModel() {
    if (data) mj_deleteData(data);
    if (model) mj_deleteModel(model);
  }
  MujocoModel(const MujocoModel&) = delete;
  MujocoModel& operator=(const MujocoModel&) = delete;
};

// Where limber body i's joint lives in MuJoCo's qpos and qvel (MuJoCo numbers bodies depth-first
// in file order, which need not be limber's order).
struct MujocoJoint {
  int position = -1, velocity = -1;
};

std::vector<MujocoJoint> joint_addresses(const ArticulatedTree& tree, const mjModel* model) {
  std::vector<MujocoJoint> addresses(static_cast<std::size_t>(tree.body_count()));
  for (int i = 0; i < tree.body_count(); ++i) {
    const int body = mj_name2id(model, mjOBJ_BODY, ("b" + std::to_string(i)).c_str());
    EXPECT_GE(body, 0);
    const int joints = model->body_jntnum[body];
    EXPECT_EQ(joints, tree.body(i).joint == ArticulatedJoint::fixed ? 0 : 1);
    if (joints == 0) continue;
    const int joint = model->body_jntadr[body];
    addresses[static_cast<std::size_t>(i)] = {model->jnt_qposadr[joint], model->jnt_dofadr[joint]};
  }
  return addresses;
}

// Copies limber's (q, v, τ) into MuJoCo's qpos, qvel, qfrc_applied (mapping above).
void set_mujoco_state(const ArticulatedTree& tree, const std::vector<MujocoJoint>& addresses, const Eigen::VectorXd& q,
                      const Eigen::VectorXd& v, const Eigen::VectorXd& tau, mjData* data) {
  for (int i = 0; i < tree.body_count(); ++i) {
    const MujocoJoint& at = addresses[static_cast<std::size_t>(i)];
    const ArticulatedJoint joint = tree.body(i).joint;
    const int p = tree.position_offset(i), d = tree.velocity_offset(i);
    for (int k = 0; k < joint_position_count(joint); ++k) data->qpos[at.position + k] = q[p + k];
    if (joint == ArticulatedJoint::floating) {
      const Eigen::Matrix3d rotation = Eigen::Quaterniond(q[p + 3], q[p + 4], q[p + 5], q[p + 6]).normalized().toRotationMatrix();
      Eigen::Vector3d::Map(data->qvel + at.velocity) = rotation * v.segment<3>(d + 3);
      Eigen::Vector3d::Map(data->qvel + at.velocity + 3) = v.segment<3>(d);
      Eigen::Vector3d::Map(data->qfrc_applied + at.velocity) = rotation * tau.segment<3>(d + 3);
      Eigen::Vector3d::Map(data->qfrc_applied + at.velocity + 3) = tau.segment<3>(d);
    } else {
      for (int k = 0; k < joint_velocity_count(joint); ++k) {
        data->qvel[at.velocity + k] = v[d + k];
        data->qfrc_applied[at.velocity + k] = tau[d + k];
      }
    }
  }
}

// limber's v̇ in MuJoCo's qacc layout and coordinates.
Eigen::VectorXd as_mujoco_accelerations(const ArticulatedTree& tree, const std::vector<MujocoJoint>& addresses, const Eigen::VectorXd& q,
                                        const Eigen::VectorXd& v, const Eigen::VectorXd& accelerations, int nv) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(nv);
  for (int i = 0; i < tree.body_count(); ++i) {
    const MujocoJoint& at = addresses[static_cast<std::size_t>(i)];
    const ArticulatedJoint joint = tree.body(i).joint;
    const int p = tree.position_offset(i), d = tree.velocity_offset(i);
    if (joint == ArticulatedJoint::floating) {
      const Eigen::Matrix3d rotation = Eigen::Quaterniond(q[p + 3], q[p + 4], q[p + 5], q[p + 6]).normalized().toRotationMatrix();
      const Eigen::Vector3d omega = v.segment<3>(d), linear = v.segment<3>(d + 3);
      out.segment<3>(at.velocity) = rotation * (accelerations.segment<3>(d + 3) + omega.cross(linear));
      out.segment<3>(at.velocity + 3) = accelerations.segment<3>(d);
    } else {
      for (int k = 0; k < joint_velocity_count(joint); ++k) out[at.velocity + k] = accelerations[d + k];
    }
  }
  return out;
}

// The tree with each body's inertia as MuJoCo compiled it (body_mass, body_ipos, body_iquat,
// body_inertia). MuJoCo diagonalizes a fullinertia with mju_eig3, whose iteration stops short of
// machine precision: the compiled inertia differs from the written one by ~1e-6 (relative), which
// alone would move the accelerations by as much. The written and compiled inertias are checked
// against each other (1e-12 for diaginertia, 1e-5 for fullinertia) and the compiled ones used.
ArticulatedTree with_compiled_inertias(const ArticulatedTree& tree, const std::vector<bool>& diagonal, const mjModel* model) {
  std::vector<ArticulatedBody> bodies = tree.bodies();
  for (int i = 0; i < tree.body_count(); ++i) {
    const int body = mj_name2id(model, mjOBJ_BODY, ("b" + std::to_string(i)).c_str());
    const mjtNum* iquat = model->body_iquat + 4 * body;
    const Eigen::Matrix3d axes = Eigen::Quaterniond(iquat[0], iquat[1], iquat[2], iquat[3]).normalized().toRotationMatrix();
    const Eigen::Matrix3d about_centre = axes * Eigen::Vector3d::Map(model->body_inertia + 3 * body).asDiagonal() * axes.transpose();
    const SpatialInertia compiled =
        SpatialInertia::from_mass_properties(model->body_mass[body], Eigen::Vector3d::Map(model->body_ipos + 3 * body), about_centre);
    const SpatialInertia& written = tree.body(i).inertia;
    const double tolerance = diagonal[static_cast<std::size_t>(i)] ? 1e-12 : 1e-5;
    EXPECT_LT((compiled.matrix() - written.matrix()).norm(), tolerance * written.matrix().norm()) << "body " << i;
    bodies[static_cast<std::size_t>(i)].inertia = compiled;
  }
  return ArticulatedTree(std::move(bodies));
}

void expect_agreement(const RandomTreeOptions& kind, std::uint32_t seed, int trees, int states_per_tree) {
  std::mt19937 rng(seed);
  const Eigen::Vector3d gravity(0.7, -1.3, -9.81);
  DynamicsWorkspace workspace;
  Eigen::VectorXd accelerations;
  for (int t = 0; t < trees; ++t) {
    const ArticulatedTree tree = random_tree(rng, kind);
    std::vector<bool> diagonal(static_cast<std::size_t>(tree.body_count()));
    for (std::size_t i = 0; i < diagonal.size(); ++i) diagonal[i] = std::bernoulli_distribution(0.5)(rng);
    const std::string mjcf = MjcfWriter(tree, diagonal).write(gravity);
    const MujocoModel mujoco(mjcf);
    ASSERT_NE(mujoco.model, nullptr) << mujoco.error << "\n" << mjcf;
    ASSERT_EQ(mujoco.model->nq, tree.position_count());
    ASSERT_EQ(mujoco.model->nv, tree.velocity_count());
    const std::vector<MujocoJoint> addresses = joint_addresses(tree, mujoco.model);
    const ArticulatedTree compiled = with_compiled_inertias(tree, diagonal, mujoco.model);
    for (int s = 0; s < states_per_tree; ++s) {
      const Eigen::VectorXd q = random_positions(rng, tree);
      const Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 2);
      const Eigen::VectorXd tau = random_vector(rng, tree.velocity_count(), 5);
      mj_resetData(mujoco.model, mujoco.data);
      set_mujoco_state(tree, addresses, q, v, tau, mujoco.data);
      mj_forward(mujoco.model, mujoco.data);
      const Eigen::VectorXd expected = Eigen::VectorXd::Map(mujoco.data->qacc, mujoco.model->nv);

      forward_dynamics(compiled, q, v, tau, gravity, workspace, accelerations);
      const Eigen::VectorXd actual = as_mujoco_accelerations(tree, addresses, q, v, accelerations, mujoco.model->nv);
      EXPECT_LT((actual - expected).norm(), 1e-9 * expected.norm())
          << "tree " << t << ", state " << s << "\nlimber: " << actual.transpose() << "\nMuJoCo: " << expected.transpose() << "\n"
          << mjcf;
    }
  }
}

TEST(MujocoAgreement, ChainsOfHingeSlideAndBallJoints) {
  expect_agreement({.bodies = 6, .joints = {ArticulatedJoint::revolute, ArticulatedJoint::prismatic, ArticulatedJoint::spherical}}, 1, 20, 5);
}

TEST(MujocoAgreement, BranchingTreesWithWeldedBodies) {
  expect_agreement({.bodies = 12, .branching = true}, 2, 20, 5);
}

TEST(MujocoAgreement, TreesOnAFreeBase) {
  expect_agreement({.bodies = 8, .branching = true, .floating_base = true}, 3, 20, 5);
}

TEST(MujocoAgreement, SingleJoints) {
  for (const ArticulatedJoint joint : {ArticulatedJoint::revolute, ArticulatedJoint::prismatic, ArticulatedJoint::spherical}) {
    expect_agreement({.bodies = 1, .joints = {joint}}, 4, 5, 5);
  }
  expect_agreement({.bodies = 1, .floating_base = true}, 5, 5, 5);
}

}  // namespace
}  // namespace limber
