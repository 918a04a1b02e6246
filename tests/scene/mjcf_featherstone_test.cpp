// MuJoCo's own humanoid (Debian's libmujoco-samples) loaded by limber and by MuJoCo 2.2.2: the
// Featherstone method's joint-space mass matrix and accelerations are MuJoCo's, with the
// armature, joint springs and damping the file gives and its 21 motors at random controls; and
// a small arm's position, velocity and motor actuators give MuJoCo's joint forces. Skipped, with
// a message, where the model file is missing.
//
// Coordinates. The hinges are the same in both (angle from the file's pose, ref = 0 in
// humanoid.xml), matched by name; the serial joints' axes are tree bodies of their own
// (featherstone_state.hpp). The floating base differs: MuJoCo's free joint moves the torso's body
// frame (qpos: its origin p and orientation R; qvel: ṗ in world, ω in the torso frame); limber's
// floating root is its torso body's frame (the torso's first capsule: origin o_l at its centre,
// orientation R_l = R·R_off), v = (ω, ȯ_l) in that frame. So v_mj = T v_l with
//   ṗ = R_l ȯ_l + (R_l ω) × (p − o_l),   ω_mj = R_off ω,   hinge rates one to one,
// and the kinetic energies agree when M_l = Tᵀ M_mj T.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/joint_space.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/rigid/bodies.hpp"
#include "limber/kernel/scene/mjcf_document.hpp"
#include "limber/kernel/scene/mjcf_model.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/test_directory.hpp"

namespace limber {
namespace {

const std::filesystem::path kHumanoid = "/usr/share/mujoco/model/humanoid/humanoid.xml";

Eigen::Matrix3d skew(const Eigen::Vector3d& r) {
  Eigen::Matrix3d m;
  m << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return m;
}

// Both engines on one file, and the map between their coordinates.
class BothEngines {
 public:
  explicit BothEngines(const std::filesystem::path& file) {
    std::vector<std::string> notes;
    model_ = model_from_mjcf(mjcf::load_mjcf(file), notes);
    state_ = compile_featherstone(model_, FeatherstoneOptions{});
    char error[1000] = "";
    mj_ = mj_loadXML(file.c_str(), nullptr, error, sizeof error);
    if (!mj_) throw std::runtime_error(std::string("mj_loadXML: ") + error);
    mj_->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_LIMIT;  // the free dynamics: no contact or limit forces
    data_ = mj_makeData(mj_);
    index_hinges();
    // The torso's frame at the file's pose in MuJoCo (its body pos and quat; its parent is the
    // world), and limber's root frame then.
    const Eigen::Quaterniond torso(mj_->body_quat[4], mj_->body_quat[5], mj_->body_quat[6], mj_->body_quat[7]);
    const Body& root = model_.bodies[0];
    rotation_offset_ = torso.toRotationMatrix().transpose() * root.orientation().toRotationMatrix();
    origin_offset_ = torso.conjugate() * (root.position - Eigen::Vector3d(mj_->body_pos[3], mj_->body_pos[4], mj_->body_pos[5]));
  }
  ~BothEngines() {
    mj_deleteData(data_);
    mj_deleteModel(mj_);
  }
  BothEngines(const BothEngines&) = delete;
  BothEngines& operator=(const BothEngines&) = delete;

  // A random state: torso pose and velocity, hinges inside their ranges, random rates.
  void set_random_state(std::mt19937& random) {
    std::uniform_real_distribution<double> unit(-1, 1);
    Eigen::Quaterniond turn(unit(random), unit(random), unit(random), unit(random));
    turn.normalize();
    const Eigen::Vector3d p(unit(random), unit(random), 10 + unit(random)), pdot(unit(random), unit(random), unit(random));
    const Eigen::Vector3d omega(2 * unit(random), 2 * unit(random), 2 * unit(random));  // torso frame
    for (int k = 0; k < 3; ++k) data_->qpos[k] = p[k], data_->qvel[k] = pdot[k], data_->qvel[3 + k] = omega[k];
    for (int a = 0; a < mj_->nu; ++a) data_->ctrl[a] = 1.2 * unit(random);  // past ctrlrange at times: clamped
    data_->qpos[3] = turn.w(), data_->qpos[4] = turn.x(), data_->qpos[5] = turn.y(), data_->qpos[6] = turn.z();
    state_.q = state_.tree.neutral_positions();
    state_.v.setZero();
    for (const Hinge& hinge : hinges_) {
      const double low = mj_->jnt_range[2 * hinge.joint], high = mj_->jnt_range[2 * hinge.joint + 1];
      const double angle = 0.5 * (low + high) + 0.45 * (high - low) * unit(random), rate = 3 * unit(random);
      data_->qpos[mj_->jnt_qposadr[hinge.joint]] = angle, data_->qvel[mj_->jnt_dofadr[hinge.joint]] = rate;
      state_.q[hinge.position] = angle, state_.v[hinge.velocity] = rate;
    }
    // limber's root: R_l = R·R_off, o_l = p + R·d; v = (R_lᵀ ω_world, R_lᵀ ȯ_l).
    rotation_ = turn.toRotationMatrix() * rotation_offset_;
    origin_ = p + turn * origin_offset_;
    torso_origin_ = p;
    const Eigen::Vector3d omega_world = turn * omega;
    const Eigen::Quaterniond root(rotation_);
    state_.q.segment<3>(0) = origin_;
    state_.q.segment<4>(3) << root.w(), root.x(), root.y(), root.z();
    state_.v.segment<3>(0) = rotation_.transpose() * omega_world;
    state_.v.segment<3>(3) = rotation_.transpose() * (pdot + omega_world.cross(origin_ - p));
  }

  // T: MuJoCo's velocities of limber's (nv × nv; see the file's comment).
  Eigen::MatrixXd velocity_map() const {
    const int nv = mj_->nv;
    Eigen::MatrixXd t = Eigen::MatrixXd::Zero(nv, nv);
    t.block<3, 3>(0, 0) = -skew(torso_origin_ - origin_) * rotation_;
    t.block<3, 3>(0, 3) = rotation_;
    t.block<3, 3>(3, 0) = rotation_offset_;
    for (const Hinge& hinge : hinges_) t(mj_->jnt_dofadr[hinge.joint], hinge.velocity) = 1;
    return t;
  }

  // The joint forces of the springs and dampers the Model holds (its drives) at limber's state,
  // and of its motors at MuJoCo's controls (gear × control clamped to its range).
  Eigen::VectorXd joint_forces() const {
    Eigen::VectorXd tau = Eigen::VectorXd::Zero(state_.tree.velocity_count());
    for (const Hinge& hinge : hinges_) {
      if (!hinge.drive) continue;
      tau[hinge.velocity] = hinge.drive->stiffness * (hinge.drive->target - state_.q[hinge.position]) - hinge.drive->damping * state_.v[hinge.velocity];
    }
    for (std::size_t a = 0; a < model_.actuators.size(); ++a) {
      const Actuator& actuator = model_.actuators[a];
      const double control = std::clamp(data_->ctrl[a], actuator.control_range->min, actuator.control_range->max);
      tau[state_.tree_joint[static_cast<std::size_t>(actuator.joint)].offset + actuator.axis] += actuator.gear * control;
    }
    return tau;
  }

  struct Hinge {
    int joint = 0;              // MuJoCo's joint id
    int position = 0, velocity = 0;  // limber's q and v index
    const JointDrive* drive = nullptr;
  };
  const std::vector<Hinge>& hinges() const { return hinges_; }
  const Model& model() const { return model_; }
  FeatherstoneState& state() { return state_; }
  mjModel* mj() const { return mj_; }
  mjData* data() const { return data_; }
  const Eigen::Matrix3d& rotation() const { return rotation_; }
  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3d& torso_origin() const { return torso_origin_; }

 private:
  // Every MuJoCo hinge, by name, to the tree's coordinate that holds it.
  void index_hinges() {
    std::map<std::string, Hinge> by_name;
    for (std::size_t j = 0; j < model_.joints.size(); ++j) {
      const Joint& joint = model_.joints[j];
      if (joint.type != JointType::revolute) continue;
      const int body = state_.tree_joint[j].body;
      by_name[joint.name] = {0, state_.tree.position_offset(body), state_.tree.velocity_offset(body), joint.drive ? &*joint.drive : nullptr};
    }
    for (const TreeSerialAxis& axis : state_.serial_axes) {
      const SerialAxis& serial = model_.joints[static_cast<std::size_t>(axis.joint)].serial_axes[static_cast<std::size_t>(axis.axis)];
      by_name[serial.name] = {0, state_.tree.position_offset(axis.body), axis.offset, serial.drive ? &*serial.drive : nullptr};
    }
    for (int j = 0; j < mj_->njnt; ++j) {
      if (mj_->jnt_type[j] != mjJNT_HINGE) continue;
      const auto found = by_name.find(mj_id2name(mj_, mjOBJ_JOINT, j));
      if (found == by_name.end()) throw std::runtime_error(std::string("no limber coordinate for hinge ") + mj_id2name(mj_, mjOBJ_JOINT, j));
      found->second.joint = j;
      hinges_.push_back(found->second);
    }
  }

  Model model_;
  FeatherstoneState state_;
  mjModel* mj_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<Hinge> hinges_;
  Eigen::Matrix3d rotation_offset_, rotation_;
  Eigen::Vector3d origin_offset_, origin_, torso_origin_;
};

#define SKIP_WITHOUT_HUMANOID()                                                                                         \
  if (!std::filesystem::exists(kHumanoid)) GTEST_SKIP() << kHumanoid << " is missing: install libmujoco-samples " \
                                                                         "(tools/install_packages.sh tests)"

TEST(MjcfHumanoid, EachBodysMassAndCentreAreMujocos) {
  SKIP_WITHOUT_HUMANOID();
  const BothEngines both(kHumanoid);
  mj_forward(both.mj(), both.data());  // xipos: each body's centre of mass in world at qpos0
  const Model& model = both.model();
  for (int b = 1; b < both.mj()->nbody; ++b) {
    const std::string name = mj_id2name(both.mj(), mjOBJ_BODY, b);
    double mass = 0;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (const Body& body : model.bodies) {
      if (body.name != name && body.name.rfind(name + "/", 0) != 0) continue;
      mass += body.mass;
      moment += body.mass * body.to_world(body_mass_properties(body).centre_of_mass);
    }
    EXPECT_NEAR(mass, both.mj()->body_mass[b], 1e-12 * mass) << name;
    const Eigen::Vector3d centre(both.data()->xipos[3 * b], both.data()->xipos[3 * b + 1], both.data()->xipos[3 * b + 2]);
    EXPECT_LT((moment / mass - centre).norm(), 1e-12) << name;
  }
}

TEST(MjcfHumanoid, MassMatrixIsMujocosWithArmature) {
  SKIP_WITHOUT_HUMANOID();
  BothEngines both(kHumanoid);
  std::mt19937 random(7);
  DynamicsWorkspace workspace;
  Eigen::MatrixXd limber_matrix;
  const int nv = both.mj()->nv;
  ASSERT_EQ(both.state().tree.velocity_count(), nv);
  std::vector<mjtNum> dense(static_cast<std::size_t>(nv * nv));
  double largest = 0;
  for (int trial = 0; trial < 20; ++trial) {
    both.set_random_state(random);
    mj_forward(both.mj(), both.data());
    mj_fullM(both.mj(), dense.data(), both.data()->qM);
    const Eigen::MatrixXd mujoco = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(dense.data(), nv, nv);
    mass_matrix(both.state().tree, both.state().q, workspace, limber_matrix);
    const Eigen::MatrixXd t = both.velocity_map();
    const Eigen::MatrixXd expected = t.transpose() * mujoco * t;
    EXPECT_LT((limber_matrix - expected).norm(), 1e-10 * expected.norm()) << "state " << trial;
    largest = std::max(largest, (limber_matrix - expected).norm() / expected.norm());
  }
  std::printf("mass matrix: largest relative difference from MuJoCo's over 20 states %.2g (Frobenius)\n", largest);
}

TEST(MjcfHumanoid, AccelerationsAreMujocosWithSpringsDampingArmatureAndMotors) {
  SKIP_WITHOUT_HUMANOID();
  BothEngines both(kHumanoid);
  std::mt19937 random(11);
  DynamicsWorkspace workspace;
  Eigen::VectorXd acceleration, forces;
  double largest = 0, largest_inverse = 0;
  const Eigen::Vector3d gravity(both.mj()->opt.gravity[0], both.mj()->opt.gravity[1], both.mj()->opt.gravity[2]);
  for (int trial = 0; trial < 20; ++trial) {
    both.set_random_state(random);
    mj_forward(both.mj(), both.data());
    FeatherstoneState& state = both.state();
    const Eigen::VectorXd tau = both.joint_forces();
    forward_dynamics(state.tree, state.q, state.v, tau, gravity, workspace, acceleration);
    const mjtNum* qacc = both.data()->qacc;
    double scale = 0;
    for (int k = 0; k < both.mj()->nv; ++k) scale = std::max(scale, std::abs(qacc[k]));
    for (const auto& hinge : both.hinges()) {
      const double mujoco = qacc[both.mj()->jnt_dofadr[hinge.joint]];
      EXPECT_NEAR(acceleration[hinge.velocity], mujoco, 1e-8 * scale) << mj_id2name(both.mj(), mjOBJ_JOINT, hinge.joint) << ", state " << trial;
      largest = std::max(largest, std::abs(acceleration[hinge.velocity] - mujoco) / scale);
    }
    // The torso: ω̇ in world, and the acceleration of MuJoCo's torso origin (limber's root origin's
    // R_l(v̇ + ω × v), carried to it as a rigid body's).
    const Eigen::Matrix3d& r = both.rotation();
    const Eigen::Vector3d omega = r * state.v.segment<3>(0), omega_dot = r * acceleration.segment<3>(0);
    const Eigen::Vector3d arm = both.torso_origin() - both.origin();
    const Eigen::Vector3d origin_acceleration =
        r * (acceleration.segment<3>(3) + state.v.segment<3>(0).cross(state.v.segment<3>(3)));
    const Eigen::Vector3d torso_acceleration = origin_acceleration + omega_dot.cross(arm) + omega.cross(omega.cross(arm));
    const Eigen::Quaterniond turn(both.data()->qpos[3], both.data()->qpos[4], both.data()->qpos[5], both.data()->qpos[6]);
    const Eigen::Vector3d mujoco_omega_dot = turn * Eigen::Vector3d(qacc[3], qacc[4], qacc[5]);
    EXPECT_LT((omega_dot - mujoco_omega_dot).norm(), 1e-8 * scale) << "state " << trial;
    EXPECT_LT((torso_acceleration - Eigen::Vector3d(qacc[0], qacc[1], qacc[2])).norm(), 1e-8 * scale) << "state " << trial;
    // Inverse dynamics of these accelerations gives the forces back (armature included).
    inverse_dynamics(state.tree, state.q, state.v, acceleration, gravity, workspace, forces);
    EXPECT_LT((forces - tau).norm(), 1e-9 * std::max(1.0, tau.norm())) << "state " << trial;
    largest = std::max({largest, (omega_dot - mujoco_omega_dot).norm() / scale,
                        (torso_acceleration - Eigen::Vector3d(qacc[0], qacc[1], qacc[2])).norm() / scale});
    largest_inverse = std::max(largest_inverse, (forces - tau).norm() / std::max(1.0, tau.norm()));
  }
  std::printf("accelerations: largest difference from MuJoCo's qacc over 20 states %.2g of the largest |qacc|; "
              "inverse dynamics returns the forces to %.2g\n", largest, largest_inverse);
}

// What each joint transmits, at 20 random states with every motor on: limber's joint_reactions
// at its own accelerations against MuJoCo's cfrc_int (mj_rnePostConstraint, contacts off) at its
// own, each moved to a torque about the joint's anchor. cfrc_int is a body's, at the subtree
// centre of mass of its tree's root, world axes: the force the parent exerts on the body.
TEST(MjcfHumanoid, JointReactionsAreMujocosInteractionForces) {
  SKIP_WITHOUT_HUMANOID();
  BothEngines both(kHumanoid);
  const Model& model = both.model();
  FeatherstoneState& state = both.state();
  const JointSpaceLayout layout = joint_space_layout(state, model);
  std::mt19937 random(23);
  double largest = 0;
  for (int trial = 0; trial < 20; ++trial) {
    both.set_random_state(random);
    refresh_rigid_bodies(state);
    mj_forward(both.mj(), both.data());
    mj_rnePostConstraint(both.mj(), both.data());
    const Eigen::VectorXd tree_forces = both.joint_forces();
    Eigen::VectorXd forces(static_cast<Eigen::Index>(layout.velocity.size()));
    for (std::size_t r = 0; r < layout.velocity.size(); ++r) forces[static_cast<Eigen::Index>(r)] = layout.velocity_sign[r] * tree_forces[layout.velocity[r]];
    const std::vector<JointReaction> reactions = joint_reactions(state, model, layout, forward_joint_dynamics(state, layout, forces));
    double scale = 0;
    for (int b = 1; b < both.mj()->nbody; ++b) scale = std::max(scale, Eigen::Map<const Eigen::Vector3d>(both.data()->cfrc_int + 6 * b + 3).norm());
    int compared = 0;
    for (std::size_t j = 0; j < model.joints.size(); ++j) {
      const Joint& joint = model.joints[j];
      const int b = mj_name2id(both.mj(), mjOBJ_BODY, model.bodies[static_cast<std::size_t>(joint.outboard)].name.c_str());
      if (b < 0) continue;  // a weld inside a compound body: no MuJoCo body of its own
      const mjtNum* wrench = both.data()->cfrc_int + 6 * b;
      const Eigen::Vector3d centre = Eigen::Map<const Eigen::Vector3d>(both.data()->subtree_com + 3 * both.mj()->body_rootid[b]);
      const Eigen::Vector3d anchor = body_point(state, static_cast<std::size_t>(joint.outboard), joint.outboard_anchor);
      const Eigen::Vector3d force(wrench[3], wrench[4], wrench[5]);
      const Eigen::Vector3d torque = Eigen::Vector3d(wrench[0], wrench[1], wrench[2]) + (centre - anchor).cross(force);
      EXPECT_LT((reactions[j].force - force).norm(), 1e-8 * scale) << joint.name << ", state " << trial;
      EXPECT_LT((reactions[j].torque - torque).norm(), 1e-8 * scale) << joint.name << ", state " << trial;
      largest = std::max({largest, (reactions[j].force - force).norm() / scale, (reactions[j].torque - torque).norm() / scale});
      ++compared;
    }
    EXPECT_EQ(compared, both.mj()->nbody - 2) << "every body but the world and the free torso";
  }
  std::printf("joint reactions: largest difference from MuJoCo's cfrc_int over 20 states %.2g of the largest force\n", largest);
}

TEST(MjcfHumanoid, TheWorldsJointSpaceIsInMujocosOrder) {
  SKIP_WITHOUT_HUMANOID();
  WorldOptions options;
  options.method = Method::featherstone;
  World world(load_scene_file(kHumanoid).model, options);
  BothEngines both(kHumanoid);
  const std::vector<std::string> names = world.joint_space_names();
  ASSERT_EQ(static_cast<int>(names.size()), both.mj()->nv);
  for (int j = 1; j < both.mj()->njnt; ++j) {  // joint 0 is the free joint: the torso's six rates
    EXPECT_EQ(names[static_cast<std::size_t>(both.mj()->jnt_dofadr[j])], mj_id2name(both.mj(), mjOBJ_JOINT, j));
  }
  // Every position named too, in MuJoCo's qpos order: the root's 3 + 4, then each hinge's angle.
  const std::vector<std::string> positions = world.joint_position_names();
  ASSERT_EQ(static_cast<int>(positions.size()), both.mj()->nq);
  EXPECT_EQ(positions[0], "torso.x");
  EXPECT_EQ(positions[3], "torso.qw");
  for (int j = 1; j < both.mj()->njnt; ++j) {
    EXPECT_EQ(positions[static_cast<std::size_t>(both.mj()->jnt_qposadr[j])], mj_id2name(both.mj(), mjOBJ_JOINT, j));
  }
  // At the file's pose the hinges' block of M is MuJoCo's, entry for entry.
  mj_forward(both.mj(), both.data());
  std::vector<mjtNum> dense(static_cast<std::size_t>(both.mj()->nv * both.mj()->nv));
  mj_fullM(both.mj(), dense.data(), both.data()->qM);
  const int nv = both.mj()->nv;
  const Eigen::MatrixXd mujoco = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(dense.data(), nv, nv);
  const Eigen::MatrixXd limber = world.joint_mass_matrix();
  EXPECT_LT((limber.bottomRightCorner(nv - 6, nv - 6) - mujoco.bottomRightCorner(nv - 6, nv - 6)).norm(),
            1e-12 * mujoco.bottomRightCorner(nv - 6, nv - 6).norm());
}

// Position, velocity and motor actuators with ref, springref, stiffness and damping on an arm
// welded to the world (so both engines' coordinates are the hinges and the slide, q = qpos − ref):
// at 20 random states and controls, limber's joint_passive_forces (the joints' springs and
// dampers and the actuators) are MuJoCo's qfrc_passive + qfrc_actuator.
TEST(MjcfActuators, PositionVelocityAndMotorForcesAreMujocos) {
  const std::string xml = R"(<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="h1" axis="0 1 0" ref="0.2" stiffness="3" springref="0.5" damping="0.4"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
      <body name="b" pos="0.3 0 0">
        <joint name="h2" axis="0 0 1" ref="-0.1" damping="0.2"/>
        <joint name="h3" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
        <body name="c" pos="0.3 0 0">
          <joint name="s" type="slide" axis="1 0 0" ref="0.05"/>
          <geom type="sphere" size="0.05"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position joint="h1" kp="20" gear="1.5"/>
    <velocity joint="h1" kv="2" gear="1.5"/>
    <position joint="h2" kp="7" ctrllimited="true" ctrlrange="-0.5 0.5"/>
    <velocity joint="h3" kv="1.3" gear="0.7"/>
    <position joint="s" kp="40" gear="2"/>
    <motor joint="h3" gear="3"/>
  </actuator>
</mujoco>)";
  const auto file = limber::testing::test_directory() / "actuators.xml";
  std::ofstream(file) << xml;
  char error[1000] = "";
  mjModel* mj = mj_loadXML(file.c_str(), nullptr, error, sizeof error);
  ASSERT_NE(mj, nullptr) << error;
  mjData* data = mj_makeData(mj);
  World world(load_scene_file(file).model, WorldOptions{.method = Method::featherstone});
  const std::vector<std::string> names = world.joint_space_names();
  ASSERT_EQ(static_cast<int>(names.size()), mj->nv);
  ASSERT_EQ(mj->nq, mj->nv);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(-1, 1);
  double largest = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd q(mj->nv), v(mj->nv);
    for (int k = 0; k < mj->nv; ++k) {
      const int j = mj_name2id(mj, mjOBJ_JOINT, names[static_cast<std::size_t>(k)].c_str());
      ASSERT_GE(j, 0) << names[static_cast<std::size_t>(k)];
      const int at = mj->jnt_qposadr[j];
      data->qpos[at] = mj->qpos0[at] + unit(random), data->qvel[mj->jnt_dofadr[j]] = 2 * unit(random);
      q[k] = data->qpos[at] - mj->qpos0[at], v[k] = data->qvel[mj->jnt_dofadr[j]];
    }
    std::vector<double> controls(static_cast<std::size_t>(mj->nu));
    for (int a = 0; a < mj->nu; ++a) controls[static_cast<std::size_t>(a)] = data->ctrl[a] = unit(random);
    mj_forward(mj, data);
    world.set_joint_state(q, v);
    world.set_controls(controls);
    const Eigen::VectorXd limber = world.joint_passive_forces();
    for (int k = 0; k < mj->nv; ++k) {
      const int dof = mj->jnt_dofadr[mj_name2id(mj, mjOBJ_JOINT, names[static_cast<std::size_t>(k)].c_str())];
      const double mujoco = data->qfrc_passive[dof] + data->qfrc_actuator[dof];
      EXPECT_NEAR(limber[k], mujoco, 1e-12 * (1 + std::abs(mujoco))) << names[static_cast<std::size_t>(k)] << ", state " << trial;
      largest = std::max(largest, std::abs(limber[k] - mujoco));
    }
  }
  std::printf("actuator and passive forces: largest difference from MuJoCo's over 20 states %.2g N·m\n", largest);
  mj_deleteData(data);
  mj_deleteModel(mj);
}

}  // namespace
}  // namespace limber
